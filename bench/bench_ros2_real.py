"""ROS 2 against real rclpy nodes (Fast DDS): `topic hz` and `topic echo` from a real publisher beside a plain
rclpy subscriber with raw=True (what `ros2 topic hz` runs), and `topic list` wall time on a real graph.

    .venv/bin/python bench/bench_ros2_real.py [--distro jazzy|kilted] [hz|echo|list]...

The peers are the tests' (tests/rclpy_peer.py in the venvs ./test.sh installs), loopback only.
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from _graph import cpu_seconds, ros2_env, rostool_cmd

from tests.ros2_peers import RclpyPeer, assert_loopback_only

RATES = ((1_000, 10_000), (10_000, 50_000), (0, 50_000))  # (msg/s, 0 = as fast as rclpy publishes; count)


def peer(distro: str, env: dict[str, str], *args: str) -> RclpyPeer:
    started = RclpyPeer(distro, env, Path(tempfile.mkdtemp(prefix="rostool-bench-")), list(args))
    started.wait_for("ready", timeout=30)
    return started


def stop_all(*peers: RclpyPeer) -> None:
    for p in peers:
        addresses = p.bound_addresses()
        p.stop()
        assert_loopback_only(addresses)


def run_burst(distro: str, rate: int, count: int, verb: list[str]) -> None:
    """One burst from a real publisher, received by rclpy (raw) and by a rostool verb at once."""
    env = ros2_env()
    anchor = peer(distro, env, "--name", "raw_counter", "--raw-count", "/bench", "--depth", "1000")
    ours = subprocess.Popen(rostool_cmd(*verb), env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)  # fmt: skip
    talker = peer(distro, env, "--name", "bench_pub", "--talk", "/bench", "--count", str(count),
                  "--rate", str(rate), "--subs", "2", "--depth", "1000")  # fmt: skip
    sent = talker.wait_for("sent", timeout=120)
    time.sleep(2.5)
    cpu = cpu_seconds(ours.pid)
    ours.send_signal(signal.SIGINT)
    out = ours.communicate(timeout=30)[0]
    counted = anchor.of("counted")[-1]
    stop_all(anchor, talker)
    true_rate = (count - 1) / sent["seconds"]
    label = f"{rate:,} msg/s" if rate else "max"
    print(f"{verb[1]} {label:>12}: sent {count} at {true_rate:,.0f} msg/s")
    raw_rate = (counted["count"] - 1) / (counted["last"] - counted["first"])
    missed = 100 * (count - counted["count"]) / count
    print(
        f"  rclpy raw=True   {counted['count']:>7} ({missed:6.2f}% missed)"
        f"  rate {raw_rate:>10,.1f} ({100 * abs(raw_rate - true_rate) / true_rate:6.2f}% error)"
    )
    if verb[1] == "hz":
        last = [json.loads(line) for line in out.splitlines() if line.startswith("{")][-1]
        got, rate_seen = last["received"], last["rate"]
        error = f"rate {rate_seen:>10,.1f} ({100 * abs(rate_seen - true_rate) / true_rate:6.2f}% error)"
    else:
        got = sum(1 for line in out.splitlines() if line.startswith("{"))
        error = ""
    missed = 100 * (count - got) / count
    print(f"  rostool {verb[1]:<8} {got:>7} ({missed:6.2f}% missed)  {error}  cpu {cpu:5.2f}s")


def bench_list(distro: str, runs: int = 10) -> None:
    env = ros2_env()
    graph = peer(distro, env, "--name", "talker", "--talk", "/chatter", "--listen", "/heard", "--params",
                 "--service", "/set_flag", "--action", "/fibonacci")  # fmt: skip
    for verb in (["topic", "list"], ["node", "list"], ["service", "list"]):
        times, complete = [], 0
        expected = {"topic": "/chatter", "node": "/talker", "service": "/set_flag"}[verb[0]]
        for _ in range(runs):
            start = time.perf_counter()
            done = subprocess.run(rostool_cmd(*verb), env=env, capture_output=True, text=True, timeout=30)
            times.append(time.perf_counter() - start)
            complete += expected in done.stdout.split()
        print(
            f"{' '.join(verb):<12} {complete}/{runs} complete  median {statistics.median(times):.2f} s  "
            f"max {max(times):.2f} s"
        )
    stop_all(graph)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--distro", default="jazzy", choices=("jazzy", "kilted"))
    parser.add_argument("what", nargs="*", default=["hz", "echo", "list"])
    args = parser.parse_args()
    print(f"real peers: {args.distro} rclpy on Fast DDS")
    for what in args.what:
        if what == "list":
            bench_list(args.distro)
            continue
        verb = ["topic", "hz", "/bench", "--json"] if what == "hz" else ["topic", "echo", "/bench", "--json"]
        for rate, count in RATES:
            run_burst(args.distro, rate, count, verb)


if __name__ == "__main__":
    main()
