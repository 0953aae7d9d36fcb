"""How soon the graph daemon's answers follow the graph (issue 21, "never stale"): a real rclpy node joins
(seconds from its `ready` until `node list` through the daemon names it) and leaves cleanly (from its exit
until no answer names it), on each backend, beside the real `ros2` with its own daemon in the same run.

    .venv/bin/python bench/latency_daemon.py [--runs 5] [--backend dds|rclpy]...

Each tool is polled with a new process per call, as a user's shell would (so each figure includes one
call's own time, about 0.1-0.3 s). A joiner carries a topic and a service of its own, so that a listing
which knew its node but not yet its endpoints would also be caught. Medians and maxima of RUNS.

`--brief N`: then N brief nodes per tool, each living BRIEF_LIFE s from its context's start (shorter than
the 3 s heartbeat of a Fast DDS ros_discovery_info writer, whose first sample a long-lived Cyclone reader
used to miss): how many `node list` named while they were alive.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from _graph import VENV_PYTHON, ros2_env

from tests.ros2_peers import BRIEF_NODE, PEERS_DIR, RclpyPeer, peer_env

DISTRO = "jazzy"
ROS2 = str(PEERS_DIR / DISTRO / "bin" / "ros2")
LIMIT = 30.0
BRIEF_LIFE = 2.5


def names(command: list[str], env: dict[str, str], verb: str) -> set[str]:
    done = subprocess.run([*command, verb, "list"], env=env, capture_output=True, text=True, timeout=60)
    return set(done.stdout.split())


def until(check: Callable[[], bool]) -> float:
    start = time.perf_counter()
    while time.perf_counter() - start < LIMIT:
        if check():
            return time.perf_counter() - start
    return float("inf")


def join_and_leave(
    command: list[str], tool_env: dict[str, str], env: dict[str, str], scratch: Path, run: int
) -> tuple[float, float]:
    """Seconds from a new node's `ready` until the tool lists it and its topic; from its exit until gone."""
    node, topic = f"/joiner_{run}", f"/joiner_topic_{run}"
    peer = RclpyPeer(
        DISTRO, env, scratch, ["--name", node[1:], "--talk", topic, "--service", f"/joiner_srv_{run}"]
    )
    peer.wait_for("ready", timeout=60)
    joined = until(
        lambda: node in names(command, tool_env, "node") and topic in names(command, tool_env, "topic")
    )
    peer.stop()
    return joined, until(lambda: node not in names(command, tool_env, "node"))


def brief_named(command: list[str], tool_env: dict[str, str], fast: dict[str, str], name: str) -> bool:
    """Whether `node list` named a node living BRIEF_LIFE s while it was alive."""
    brief = subprocess.Popen([str(PEERS_DIR / DISTRO / "bin" / "python"), "-c", BRIEF_NODE, name,
                              str(BRIEF_LIFE)], env=fast, stdout=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert brief.stdout is not None and brief.stdout.readline().strip() == "up"
        while brief.poll() is None:
            if f"/{name}" in names(command, tool_env, "node"):
                return True
        return False
    finally:
        brief.communicate(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--backend", action="append", choices=("dds", "rclpy"))
    parser.add_argument("--brief", type=int, default=0, help="brief nodes per tool (see above)")
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="rtl"))
    run_dir = scratch / "run"
    run_dir.mkdir(mode=0o700)
    env = {**ros2_env(), "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(run_dir),
           "XDG_STATE_HOME": str(scratch / "state"), "ROSTOOL_DAEMON_BUILD": "latency"}  # fmt: skip
    fast = peer_env(env, scratch)
    tools = {"ros2": ([ROS2], fast)}
    for backend in args.backend or ["dds", "rclpy"]:
        python = VENV_PYTHON if backend == "dds" else str(PEERS_DIR / DISTRO / "bin" / "python")
        tools[f"rostool {backend}"] = ([python, "-m", "rostool", "--ros2-backend", backend],
                                       env if backend == "dds" else fast)  # fmt: skip
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    steady = RclpyPeer(DISTRO, env, scratch, ["--name", "steady"])
    try:
        for command, tool_env in tools.values():
            subprocess.run([*command, "daemon", "start"], env=tool_env, capture_output=True, timeout=60)
        steady.wait_for("ready", timeout=60)
        for command, tool_env in tools.values():  # every daemon knows the steady graph before the runs
            until(lambda c=command, e=tool_env: "/steady" in names(c, e, "node"))
        joins: dict[str, list[float]] = {label: [] for label in tools}
        leaves: dict[str, list[float]] = {label: [] for label in tools}
        for run in range(args.runs):
            for label, (command, tool_env) in tools.items():
                joined, left = join_and_leave(command, tool_env, env, scratch, run)
                joins[label].append(joined)
                leaves[label].append(left)
        print("| tool | join: ready -> listed (median, max) | clean leave: exit -> gone (median, max) |")
        print("|---|---|---|")
        for label in tools:
            print(f"| {label} | {statistics.median(joins[label]):.2f} s, {max(joins[label]):.2f} s | "
                  f"{statistics.median(leaves[label]):.2f} s, {max(leaves[label]):.2f} s |")  # fmt: skip
        if args.brief:
            print(f"\n| tool | brief nodes ({BRIEF_LIFE:g} s) named while alive |\n|---|---|")
            for label, (command, tool_env) in tools.items():
                named = sum(brief_named(command, tool_env, fast, f"brief_{label.split()[-1]}_{k}")
                            for k in range(args.brief))  # fmt: skip
                print(f"| {label} | {named} / {args.brief} |", flush=True)
    finally:
        steady.stop()
        for command, tool_env in tools.values():
            subprocess.run([*command, "daemon", "stop"], env=tool_env, capture_output=True, timeout=60)
        shutil.rmtree(scratch, ignore_errors=True)
    print(f"load average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
