"""Listings through rostool's graph daemon beside the real `ros2` with its own warm daemon, on one graph of
real rclpy nodes (>= 10 nodes, >= 40 topics, services, actions; Fast DDS on loopback), in one run.

    .venv/bin/python bench/bench_daemon.py [--runs 20] [--cold 5] [--backend dds|rclpy]... [--cold-only]
        [--then] [--cold-at-once N]

Each call is a new process, as a user's shell runs it; calls of the two tools alternate, so a drift of the
machine's speed touches both. `complete` counts the runs whose answer held every name the graph has.
Cold: no daemon yet (it is stopped before each run): the call answers directly while it starts one.
`--cold-only` measures only that (and the empty graph), not the warm calls; `--then` also times the same
call made right after each cold one (answered by the daemon it started, or directly); `--cold-at-once N`
starts N `topic list` together with no daemon yet.
"""

from __future__ import annotations

import argparse
import json
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
NODES = 10
Check = Callable[[str], bool]


def start_graph(env: dict[str, str], scratch: Path) -> tuple[list[RclpyPeer], dict[str, set[str]]]:
    """NODES peers, each with 4 topics of its own; 3 services and 2 actions among them."""
    peers, expected = [], {"node": set(), "topic": set(), "service": set(), "action": set()}
    for i in range(NODES):
        args = ["--name", f"bench_{i}", "--talk", f"/talk_{i}", "--rate", "2",
                "--listen", f"/talk_{(i + 1) % NODES}", "--repeat", f"std_msgs/msg/Int32=/count_{i}",
                "--repeat", f"std_msgs/msg/Float64=/value_{i}", "--stamped", f"/point_{i}"]  # fmt: skip
        expected["topic"] |= {f"/talk_{i}", f"/count_{i}", f"/value_{i}", f"/point_{i}"}
        if i < 3:
            args += ["--service", f"/set_{i}"]
            expected["service"].add(f"/set_{i}")
        if i < 2:
            args += ["--action", f"/fib_{i}"]
            expected["action"].add(f"/fib_{i}")
        expected["node"].add(f"/bench_{i}")
        peers.append(RclpyPeer(DISTRO, env, scratch, args))
    for peer in peers:
        peer.wait_for("ready", timeout=60)
    return peers, expected


def timed(command: list[str], env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess[str]]:
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
    return time.perf_counter() - start, done


def row(label: str, times: list[float], complete: int) -> str:
    return f"| {label} | {statistics.median(times):.3f} s | {max(times):.3f} s | {complete}/{len(times)} |"


def warmed(command: list[str], env: dict[str, str], check: Check, limit: float = 30.0) -> float:
    """Seconds until a tool's warm daemon gives a complete node list (each tool gets the same chance)."""
    start = time.perf_counter()
    while time.perf_counter() - start < limit:
        done = subprocess.run([*command, "node", "list"], env=env, capture_output=True, text=True, timeout=60)
        if done.returncode == 0 and check(done.stdout):
            break
    return time.perf_counter() - start


def at_once(command: list[str], env: dict[str, str], topics: set[str], label: str, calls: int = 50) -> str:
    """CALLS `topic list` started together: how many answered complete, and the wall time of all."""
    start = time.perf_counter()
    quiet = {"stdout": subprocess.PIPE, "stderr": subprocess.DEVNULL, "text": True}
    running = [subprocess.Popen(command, env=env, **quiet) for _ in range(calls)]  # type: ignore[call-overload]
    outputs = [(proc.communicate(timeout=120)[0], proc.returncode) for proc in running]
    complete = sum(code == 0 and topics <= set(out.split()) for out, code in outputs)
    seconds = time.perf_counter() - start
    return f"| {calls} x topic list at once, {label} | {seconds:.2f} s (all) | | {complete}/{calls} |"


def until_serving(command: list[str], env: dict[str, str], limit: float = 30.0) -> float:
    """perf_counter() once the daemon a cold call started answers `daemon status` (a cold call starts it as
    it ends, so the next run's `daemon stop` could otherwise come before it holds its lock, and that run
    would be answered by it, warm)."""
    deadline = time.perf_counter() + limit
    while time.perf_counter() < deadline:
        done = subprocess.run(
            [*command, "daemon", "status", "--json"], env=env, capture_output=True, text=True, timeout=60
        )
        if done.returncode == 0 and json.loads(done.stdout).get("running") is True:
            break
        time.sleep(0.05)
    return time.perf_counter()


def verbs(expected: dict[str, set[str]]) -> list[tuple[list[str], Check]]:
    def holds(kind: str) -> Check:
        return lambda out: expected[kind] <= set(out.split())

    return [
        (["topic", "list"], holds("topic")),
        (["node", "list"], lambda out: set(out.split()) == expected["node"]),
        (["service", "list"], holds("service")),
        (["action", "list"], holds("action")),
        (["topic", "type", "/talk_0"], lambda out: out.strip() == "std_msgs/msg/String"),
        (["node", "info", "/bench_0"], lambda out: "/talk_0: std_msgs/msg/String" in out and "/fib_0" in out),
    ]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--cold", type=int, default=5)
    parser.add_argument("--backend", action="append", choices=("dds", "rclpy"))
    parser.add_argument("--cold-only", action="store_true")
    parser.add_argument("--then", action="store_true", help="time a second call right after each cold one")
    parser.add_argument("--cold-at-once", type=int, default=0, help="N `topic list` at once, no daemon yet")
    args = parser.parse_args()
    backends = args.backend or ["dds", "rclpy"]
    scratch = Path(tempfile.mkdtemp(prefix="rtb"))
    run_dir = scratch / "run"
    run_dir.mkdir(mode=0o700)
    # the build is pinned: a checkout edited during the run would otherwise have its daemons replaced
    env = {**ros2_env(), "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(run_dir),
           "XDG_STATE_HOME": str(scratch / "state"), "ROSTOOL_DAEMON_BUILD": "bench"}  # fmt: skip
    fast = peer_env(env, scratch)  # ros2's (and the rclpy backend's) environment: Fast DDS on loopback
    tools = {
        "dds": ([VENV_PYTHON, "-m", "rostool", "--ros2-backend", "dds"], env),
        "rclpy": (
            [str(PEERS_DIR / DISTRO / "bin" / "python"), "-m", "rostool", "--ros2-backend", "rclpy"],
            fast,
        ),
    }
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    # every daemon starts before the graph: with the loopback profile a Fast DDS participant only probes
    # the first participant ids on 127.0.0.1, so one started after ten peers would miss some of them
    subprocess.run([ROS2, "daemon", "start"], env=fast, check=True, capture_output=True, timeout=60)
    for backend in backends:
        command, tool_env = tools[backend]
        subprocess.run(
            [*command, "daemon", "start"], env=tool_env, check=True, capture_output=True, timeout=60
        )
    peers, expected = start_graph(env, scratch)
    print(f"graph: {NODES} nodes, {len(expected['topic']) + 2} topics, {len(expected['service'])} services "
          f"(+ each node's parameter services), {len(expected['action'])} actions")  # fmt: skip
    try:
        all_nodes = verbs(expected)[1][1]
        print(f"ros2's daemon complete after {warmed([ROS2], fast, all_nodes):.1f} s")
        for backend in [] if args.cold_only else backends:
            command, tool_env = tools[backend]
            print(f"rostool's {backend} daemon complete after {warmed(command, tool_env, all_nodes):.1f} s")
            print(f"\nwarm, {backend} backend: | verb | median | max | complete |")
            for verb, check in verbs(expected):
                ours, theirs, ours_ok, theirs_ok = [], [], 0, 0
                for _ in range(args.runs):
                    seconds, done = timed([*command, *verb], tool_env)
                    ours.append(seconds)
                    ours_ok += done.returncode == 0 and check(done.stdout)
                    seconds, done = timed([ROS2, *verb], fast)
                    theirs.append(seconds)
                    theirs_ok += done.returncode == 0 and check(done.stdout)
                ratio = statistics.median(ours) / statistics.median(theirs)
                print(row(f"rostool {' '.join(verb)}", ours, ours_ok), f" {ratio:.2f}x ros2")
                print(row(f"ros2 {' '.join(verb)}", theirs, theirs_ok))
            print(at_once([*command, "topic", "list"], tool_env, expected["topic"], f"rostool ({backend})"))
        if not args.cold_only:
            print(at_once([ROS2, "topic", "list"], fast, expected["topic"], "ros2"))
        for backend in backends:
            command, tool_env = tools[backend]
            for verb, check in verbs(expected)[:2]:  # topic list, node list
                cold, cold_ok, serving, then, then_ok = [], 0, [], [], 0
                for _ in range(args.cold):
                    subprocess.run(
                        [*command, "daemon", "stop"], env=tool_env, capture_output=True, timeout=60
                    )
                    start = time.perf_counter()
                    seconds, done = timed([*command, *verb], tool_env)
                    cold.append(seconds)
                    cold_ok += done.returncode == 0 and check(done.stdout)
                    if args.then:  # the same call again at once, as a shell script would
                        seconds, done = timed([*command, *verb], tool_env)
                        then.append(seconds)
                        then_ok += done.returncode == 0 and check(done.stdout)
                    serving.append(until_serving(command, tool_env) - start)
                served = f"{statistics.median(serving):.2f} s (max {max(serving):.2f} s) after the call began"
                print(row(f"cold rostool {' '.join(verb)} ({backend})", cold, cold_ok),
                      f" min {min(cold):.3f} s; the daemon it started answered {served}")  # fmt: skip
                if then:
                    print(row(f"the same call right after ({backend})", then, then_ok))
            if args.cold_at_once:
                subprocess.run([*command, "daemon", "stop"], env=tool_env, capture_output=True, timeout=60)
                label, calls = f"rostool ({backend}), no daemon yet", args.cold_at_once
                print(at_once([*command, "topic", "list"], tool_env, expected["topic"], label, calls))
                until_serving(command, tool_env)
        empty = {**env, **ros2_env()}
        kept = ("ROSTOOL_NO_DAEMON", "XDG_RUNTIME_DIR", "XDG_STATE_HOME", "ROSTOOL_DAEMON_BUILD")
        empty.update({k: env[k] for k in kept})
        command, _ = tools["dds"]
        subprocess.run([*command, "daemon", "start"], env=empty, check=True, capture_output=True, timeout=60)
        quiet, quiet_ok = [], 0
        for _ in range(args.runs):
            seconds, done = timed([*command, "topic", "list"], empty)
            quiet.append(seconds)
            quiet_ok += done.returncode == 0 and done.stdout == ""
        print(row("empty graph, warm: rostool topic list (dds)", quiet, quiet_ok))
    finally:
        tear_down_ros2(env, fast, ROS2, peers, scratch)


if __name__ == "__main__":
    main()
