"""The listing verbs, each tool with and without its daemon (issue 22): the real `ros2` (its warm daemon, and
`--no-daemon`), rostool on each backend (its warm daemon, and ROSTOOL_NO_DAEMON=1), on one graph of real
rclpy nodes (Fast DDS, loopback), in one run.

    .venv/bin/python bench/bench_listing.py [--runs 3] [--nodes 4] [--backend dds|rclpy]...

Each call is a new process, as a user's shell runs it; the tools alternate within each run, so a drift of
the machine's speed touches all of them. `complete` counts the answers that held every name of the graph.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from _graph import VENV_PYTHON, ros2_env, tear_down_ros2

from tests.ros2_peers import PEERS_DIR, RclpyPeer, peer_env

DISTRO = "jazzy"
ROS2 = str(PEERS_DIR / DISTRO / "bin" / "ros2")
Check = Callable[[str], bool]
Tool = tuple[str, list[str], dict[str, str]]


def start_graph(
    nodes: int, env: dict[str, str], scratch: Path
) -> tuple[list[RclpyPeer], dict[str, set[str]]]:
    """NODES peers, each with 2 topics of its own and a service; one action."""
    peers, expected = [], {"node": set(), "topic": set(), "service": set(), "action": set()}
    for i in range(nodes):
        args = ["--name", f"lst_{i}", "--talk", f"/talk_{i}", "--rate", "2", "--stamped", f"/point_{i}",
                "--listen", f"/talk_{(i + 1) % nodes}", "--service", f"/set_{i}"]  # fmt: skip
        if i == 0:
            args += ["--action", "/fib"]
            expected["action"].add("/fib")
        expected["node"].add(f"/lst_{i}")
        expected["topic"] |= {f"/talk_{i}", f"/point_{i}"}
        expected["service"].add(f"/set_{i}")
        peers.append(RclpyPeer(DISTRO, env, scratch, args))
    for peer in peers:
        peer.wait_for("ready", timeout=60)
    return peers, expected


def verbs(expected: dict[str, set[str]]) -> list[tuple[list[str], Check]]:
    def holds(kind: str) -> Check:
        return lambda out: expected[kind] <= set(out.split())

    return [
        (["node", "list"], holds("node")),
        (["topic", "list"], holds("topic")),
        (["service", "list"], holds("service")),
        (["action", "list"], holds("action")),
        (["topic", "info", "/talk_0"], lambda out: "Publisher count: 1" in out),
        (["node", "info", "/lst_0"], lambda out: "/talk_0: std_msgs/msg/String" in out),
    ]


def timed(command: list[str], env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess[str]]:
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
    return time.perf_counter() - start, done


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--nodes", type=int, default=4)
    parser.add_argument("--backend", action="append", choices=("dds", "rclpy"))
    args = parser.parse_args()
    backends = args.backend or ["dds", "rclpy"]
    scratch = Path(tempfile.mkdtemp(prefix="rtl"))
    run_dir = scratch / "run"
    run_dir.mkdir(mode=0o700)
    # the build is pinned: a checkout edited during the run would otherwise have its daemons replaced
    env = {**ros2_env(), "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(run_dir),
           "XDG_STATE_HOME": str(scratch / "state"), "ROSTOOL_DAEMON_BUILD": "bench"}  # fmt: skip
    fast = peer_env(env, scratch)  # ros2's (and the rclpy backend's) environment: Fast DDS on loopback
    tools: list[Tool] = [("ros2, its daemon", [ROS2], fast), ("ros2 --no-daemon", [ROS2], fast)]
    for backend in backends:
        python = VENV_PYTHON if backend == "dds" else str(PEERS_DIR / DISTRO / "bin" / "python")
        command = [python, "-m", "rostool", "--ros2", "--ros2-backend", backend]
        tool_env = env if backend == "dds" else fast
        tools.append((f"rostool {backend}, its daemon", command, tool_env))
        tools.append((f"rostool {backend}, no daemon", command, {**tool_env, "ROSTOOL_NO_DAEMON": "1"}))
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    # every daemon starts before the graph (a Fast DDS participant started after the peers may probe too
    # few participant ids on loopback to find them all), and each answers a first listing before timing
    subprocess.run([ROS2, "daemon", "start"], env=fast, check=True, capture_output=True, timeout=60)
    for label, command, tool_env in tools:
        if label.startswith("rostool") and label.endswith("its daemon"):
            subprocess.run([*command, "daemon", "start"], env=tool_env, check=True, capture_output=True,
                           timeout=60)  # fmt: skip
    peers, expected = start_graph(args.nodes, env, scratch)
    print(f"graph: {args.nodes} nodes, {len(expected['topic'])} topics, {len(expected['service'])} "
          f"services (+ parameter services), 1 action; {args.runs} runs each")  # fmt: skip
    try:
        time.sleep(2.0)  # the daemons discover the peers before anything is timed
        results: dict[tuple[str, str], list[tuple[float, bool]]] = {}
        for verb, check in verbs(expected):
            for _ in range(args.runs):
                for label, command, tool_env in tools:
                    extra = ["--no-daemon"] if label == "ros2 --no-daemon" else []
                    seconds, done = timed([*command, *verb, *extra], tool_env)
                    ok = done.returncode == 0 and check(done.stdout)
                    results.setdefault((" ".join(verb), label), []).append((seconds, ok))
        print("\n| verb | tool | median | min | max | complete |\n|---|---|---|---|---|---|")
        for (verb, label), runs in results.items():
            times = [s for s, _ in runs]
            print(f"| {verb} | {label} | {statistics.median(times):.2f} s | {min(times):.2f} | "
                  f"{max(times):.2f} | {sum(ok for _, ok in runs)}/{len(runs)} |")  # fmt: skip
    finally:
        tear_down_ros2(env, fast, ROS2, peers, scratch)


if __name__ == "__main__":
    main()
