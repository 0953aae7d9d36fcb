"""`rostool bag burst` vs Debian's `rosbag play --immediate`: how fast N messages go out, and how many a
subscriber receives.

    .venv/bin/python bench/bench_bag_burst.py [--count 20000] [--runs 3]

Generates a ROS 1 bag of COUNT std_msgs/Int32, starts Debian's rosmaster on a free 127.0.0.1 port and one
raw subscriber (rostool's own ROS 1 node, in this process) that timestamps each arrival. Each player
publishes the whole bag as fast as it can (`--wait-for-subscribers -q`, rosbag: `--immediate`),
alternating, RUNS times. Reported per player: the median over runs of messages per second between the
first and the last arrival, wall time of the whole command, and messages lost.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _graph import debian_env, free_port, ros1_env, start_master
from bench_bag_play import Receiver, write_bag


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--count", type=int, default=20000)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        bag = work / "numbers.bag"
        count = write_bag(bag, 1000, args.count / 1000)
        port = free_port()
        env = ros1_env(port, work)
        os.environ.update({k: v for k, v in env.items() if k.startswith("ROS")})
        master = start_master(env)
        try:
            receiver = Receiver()
            commands = {
                "rostool": ([sys.executable, "-m", "rostool", "bag", "burst", "-d", "0"], env),
                "rosbag": (["rosbag", "play", "--immediate", "-d", "0"], debian_env(env)),
            }
            rates: dict[str, list[float]] = {name: [] for name in commands}
            walls: dict[str, list[float]] = {name: [] for name in commands}
            lost: dict[str, int] = {name: 0 for name in commands}
            for run in range(args.runs):
                for name, (command, run_env) in commands.items():
                    started = time.perf_counter()
                    subprocess.run(
                        [*command, "--wait-for-subscribers", "-q", str(bag)],
                        env=run_env,
                        check=True,
                        stdout=subprocess.DEVNULL,
                        timeout=300,
                    )
                    walls[name].append(time.perf_counter() - started)
                    time.sleep(0.5)  # the last messages still in the socket
                    arrivals = receiver.take()
                    span = arrivals[-1][0] - arrivals[0][0] if len(arrivals) > 1 else float("nan")
                    rates[name].append((len(arrivals) - 1) / span)
                    lost[name] += count - len(arrivals)
                    print(f"run {run + 1} {name}: {len(arrivals)} messages in {span:.3f} s", file=sys.stderr)
            receiver.node.close()
        finally:
            master.terminate()
            master.wait(10)
    print(f"\n{count} std_msgs/Int32, {args.runs} runs each:")
    for name in commands:
        print(
            f"{name:>8}: {statistics.median(rates[name]):,.0f} msg/s received, "
            f"{statistics.median(walls[name]):.2f} s wall per run, lost {lost[name]} of {count * args.runs}"
        )
    ratio = statistics.median(rates["rostool"]) / statistics.median(rates["rosbag"])
    print(f"\nratio rostool/rosbag: {ratio:.2f}x messages per second (above 1: rostool bursts faster)")


if __name__ == "__main__":
    main()
