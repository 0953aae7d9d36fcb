"""`rostool bag play` vs Debian's `rosbag play`: how close to its schedule each message is published.

    .venv/bin/python bench/bench_bag_play.py [--rate-hz 1000] [--seconds 5] [--runs 3]

Generates a ROS 1 bag of std_msgs/Int32 stamped at RATE_HZ for SECONDS, starts Debian's rosmaster on a
free 127.0.0.1 port and one raw subscriber (rostool's own ROS 1 node, in this process) that timestamps
each message on arrival. Each player then plays the bag (`--wait-for-subscribers -q`), alternating,
RUNS times. For every message: error = arrival - (first arrival + (stamp - first stamp)), then the
constant part (network latency) is removed by subtracting the median error; the numbers reported are
the median, 99th percentile and maximum of |error|, in milliseconds, and the messages lost.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
import xmlrpc.client
from pathlib import Path
from typing import Any

from _graph import debian_env, free_port, ros1_env

T0 = 1_700_000_000_000_000_000


def write_bag(path: Path, rate_hz: int, seconds: float) -> int:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    count = int(rate_hz * seconds)
    period = 1_000_000_000 // rate_hz
    with Writer(path) as writer:
        conn = writer.add_connection("/numbers", "std_msgs/msg/Int32", typestore=store)
        for i in range(count):
            writer.write(conn, T0 + i * period, struct.pack("<i", i))
    return count


class Receiver:
    def __init__(self) -> None:
        from rostool.graph.ros1.node import Node

        self.node = Node("bench_play_rx")
        self.arrivals: list[tuple[float, int]] = []
        self.lock = threading.Lock()
        self.node.subscribe("/numbers", self.on_message)

    def on_message(self, payload: bytes, _link: Any) -> None:
        now = time.perf_counter()
        self.arrivals.append((now, struct.unpack("<i", payload)[0]))

    def take(self) -> list[tuple[float, int]]:
        arrivals, self.arrivals = self.arrivals, []
        return arrivals


def errors(arrivals: list[tuple[float, int]], period_s: float) -> list[float]:
    first_t, first_i = arrivals[0]
    raw = [t - first_t - (i - first_i) * period_s for t, i in arrivals]
    offset = statistics.median(raw)
    return [abs(e - offset) * 1000.0 for e in raw]


def summarize(name: str, runs: list[tuple[list[float], int]], count: int) -> dict[str, float]:
    all_errors = sorted(e for errs, _lost in runs for e in errs)
    lost = sum(lost for _errs, lost in runs)
    p99 = all_errors[int(0.99 * (len(all_errors) - 1))]
    result = {"median": statistics.median(all_errors), "p99": p99, "max": all_errors[-1], "lost": lost}
    print(
        f"{name:>8}: median {result['median']:.3f} ms   p99 {p99:.3f} ms   max {result['max']:.3f} ms   "
        f"lost {lost} of {count * len(runs)}"
    )
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rate-hz", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        bag = work / "numbers.bag"
        count = write_bag(bag, args.rate_hz, args.seconds)
        port = free_port()
        env = ros1_env(port, work)
        os.environ.update({k: v for k, v in env.items() if k.startswith("ROS")})
        master = subprocess.Popen(
            ["rosmaster", "--core", "-p", str(port)],
            env=debian_env(env),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            proxy: Any = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
            deadline = time.monotonic() + 20
            while True:
                try:
                    proxy.getPid("/bench")
                    break
                except OSError:
                    if time.monotonic() > deadline:
                        raise SystemExit("rosmaster did not start") from None
                    time.sleep(0.05)
            receiver = Receiver()
            commands = {
                "rostool": ([sys.executable, "-m", "rostool", "bag", "play"], env),
                "rosbag": (["rosbag", "play"], debian_env(env)),
            }
            results: dict[str, list[tuple[list[float], int]]] = {name: [] for name in commands}
            cpu: dict[str, float] = {name: 0.0 for name in commands}
            for run in range(args.runs):
                for name, (command, run_env) in commands.items():
                    before = resource.getrusage(resource.RUSAGE_CHILDREN)
                    subprocess.run(
                        [*command, "--wait-for-subscribers", "-q", str(bag)],
                        env=run_env,
                        check=True,
                        stdout=subprocess.DEVNULL,
                        timeout=args.seconds * 4 + 30,
                    )
                    after = resource.getrusage(resource.RUSAGE_CHILDREN)
                    cpu[name] += (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                    time.sleep(0.3)
                    arrivals = receiver.take()
                    results[name].append((errors(arrivals, 1.0 / args.rate_hz), count - len(arrivals)))
                    print(f"run {run + 1} {name}: {len(arrivals)} messages", file=sys.stderr)
            receiver.node.close()
        finally:
            master.terminate()
            master.wait(10)
    print(f"\n{count} std_msgs/Int32 at {args.rate_hz} Hz, {args.runs} runs each; |arrival - schedule|:")
    ours = summarize("rostool", results["rostool"], count)
    theirs = summarize("rosbag", results["rosbag"], count)
    for name, seconds in cpu.items():
        print(f"{name:>8}: {seconds / args.runs:.2f} s of CPU per run of {args.seconds:g} s")
    print(
        f"\nratio rostool/rosbag: median {ours['median'] / theirs['median']:.2f}x, "
        f"p99 {ours['p99'] / theirs['p99']:.2f}x (below 1: rostool is closer to the schedule)"
    )


if __name__ == "__main__":
    main()
