"""`topic hz` and `topic echo` of a fast real publisher, through the graph daemon's relay and directly, side
by side in one run, each beside a plain rclpy subscriber with raw=True (what `ros2 topic hz` runs):

    .venv/bin/python bench/bench_relay.py [--distro jazzy|kilted] [--runs 2] [--rates 1000 10000]

A relayed verb's reader lives in the daemon, which streams the messages over its Unix socket: the table
shows what each got, the rate hz measured, and the CPU of the verb and (relayed) of the daemon. The talker
(tests/rclpy_peer.py --count) starts its burst once the raw counter and the verb are subscribed.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path

from _graph import cpu_seconds, ros2_env, rostool_cmd

from tests.ros2_peers import RclpyPeer, assert_loopback_only

BURST_SECONDS = 5


def peer(distro: str, env: dict[str, str], scratch: Path, *args: str) -> RclpyPeer:
    started = RclpyPeer(distro, env, scratch, list(args))
    started.wait_for("ready", timeout=30)
    return started


def burst(
    distro: str, env: dict[str, str], scratch: Path, rate: int, verb: list[str], daemon: int | None
) -> str:
    count = rate * BURST_SECONDS
    anchor = peer(distro, env, scratch, "--name", "raw_counter", "--raw-count", "/bench", "--depth", "1000")
    ours = subprocess.Popen(rostool_cmd(*verb), env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(ours.stdout or ()), daemon=True)
    reader.start()  # read as it comes: a full pipe would stall echo, not the relay
    daemon_cpu = cpu_seconds(daemon) if daemon else 0.0
    talker = peer(distro, env, scratch, "--name", "bench_pub", "--talk", "/bench", "--count", str(count),
                  "--rate", str(rate), "--subs", "2", "--depth", "1000")  # fmt: skip
    try:
        sent = talker.wait_for("sent", timeout=120)
        time.sleep(2.5)  # the last messages arrive
        cpu = cpu_seconds(ours.pid)
        daemon_cpu = cpu_seconds(daemon) - daemon_cpu if daemon else 0.0
        ours.send_signal(signal.SIGINT)
        ours.wait(timeout=30)
        reader.join(10)
        counted = anchor.of("counted")[-1]["count"]
    finally:
        for running in (anchor, talker):
            addresses = running.bound_addresses()
            running.stop()
            assert_loopback_only(addresses)
    true_rate = (count - 1) / sent["seconds"]
    records = [json.loads(line) for line in lines if line.startswith("{")]
    got = records[-1]["received"] if verb[1] == "hz" and records else len(records)
    measured = f"{records[-1]['rate']:,.1f}" if verb[1] == "hz" and records else "-"
    daemon_text = f"{daemon_cpu:.2f} s" if daemon else "-"
    return (f"| {verb[1]} | {rate:,} ({true_rate:,.0f}) | {got:,} of {count:,} | {measured} | {counted:,} | "
            f"{cpu:.2f} s | {daemon_text} |")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--distro", default="jazzy", choices=("jazzy", "kilted"))
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--rates", type=int, nargs="+", default=[1000, 10000])
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="rtr"))
    run_dir = scratch / "run"
    run_dir.mkdir(mode=0o700)
    base = {**ros2_env(), "XDG_RUNTIME_DIR": str(run_dir), "XDG_STATE_HOME": str(scratch / "state")}
    relayed, direct = {**base, "ROSTOOL_NO_DAEMON": ""}, {**base, "ROSTOOL_NO_DAEMON": "1"}
    subprocess.run(rostool_cmd("daemon", "start"), env=relayed, capture_output=True, timeout=60)
    status = subprocess.run(rostool_cmd("daemon", "status", "--json"), env=relayed, capture_output=True,
                            text=True, timeout=30)  # fmt: skip
    daemon = int(json.loads(status.stdout)["pid"])
    print(f"{args.distro} talker (rclpy, Fast DDS, loopback), rostool's DDS backend; load average at start "
          f"{os.getloadavg()[0]:.1f}")  # fmt: skip
    print("| verb | msg/s asked (sent) | rostool got | hz's rate | rclpy raw got | verb CPU | daemon CPU |")
    print("|---|---|---|---|---|---|---|")
    try:
        for _ in range(args.runs):
            for name in ("hz", "echo"):
                verb = ["topic", name, "/bench", "--json"]
                for rate in args.rates:
                    for label, env, pid in (("relayed", relayed, daemon), ("direct", direct, None)):
                        print(burst(args.distro, env, scratch, rate, verb, pid).replace(
                            f"| {name} |", f"| {name} ({label}) |"), flush=True)  # fmt: skip
    finally:
        subprocess.run(rostool_cmd("daemon", "stop", "--all"), env=relayed, capture_output=True, timeout=60)
        print(f"load average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
