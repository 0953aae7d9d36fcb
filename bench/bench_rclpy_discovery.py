"""How long a bare rclpy node (no rostool) takes to see peers that already run: the floor of any direct
listing on the rclpy backend, whatever the tool (issue 21's cold call).

    .venv/bin/python bench/bench_rclpy_discovery.py [--distro jazzy|kilted] [--runs 10] [--peers 3]

PEERS real rclpy talkers (tests/rclpy_peer.py, Fast DDS on the tests' loopback profile) start first; then
RUNS fresh processes of the distro's own Python, one after the other, each a context and a node that polls
the rmw graph every 10 ms until every peer's topic is listed. Printed: seconds from the node's creation
until the first and the last peer were seen, per run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import tempfile
from pathlib import Path

from _graph import ros2_env

from tests.ros2_peers import RclpyPeer, peer_env, peer_python

PROBE = r"""
import json, sys, time
import rclpy
want = set(sys.argv[1:])
context = rclpy.Context()
rclpy.init(context=context)
node = rclpy.create_node("discovery_probe", context=context)
made, seen = time.monotonic(), {}
while len(seen) < len(want) and time.monotonic() - made < 10:
    listed = {name for name, _types in node.get_topic_names_and_types()}
    for topic in (want & listed) - set(seen):
        seen[topic] = time.monotonic() - made
    time.sleep(0.01)
node.destroy_node()
rclpy.shutdown(context=context)
print(json.dumps(seen))
"""


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--distro", default="jazzy")
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--peers", type=int, default=3)
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="rtd"))
    env = ros2_env()
    topics = [f"/seen_{i}" for i in range(args.peers)]
    peers = [RclpyPeer(args.distro, env, scratch, ["--name", f"seen_{i}", "--talk", topic])
             for i, topic in enumerate(topics)]  # fmt: skip
    try:
        for peer in peers:
            peer.wait_for("ready", timeout=60)
        probe = [str(peer_python(args.distro)), "-c", PROBE, *topics]
        probe_env = peer_env(env, scratch)
        firsts, lasts = [], []
        print(f"| run | first peer seen | last peer seen | seen |  ({args.distro}, {args.peers} peers)")
        for run in range(1, args.runs + 1):
            done = subprocess.run(probe, env=probe_env, capture_output=True, text=True, timeout=60)
            seen = json.loads(done.stdout.strip().splitlines()[-1])
            times = sorted(seen.values()) or [float("nan")]
            firsts.append(times[0])
            lasts.append(times[-1])
            print(f"| {run} | {times[0]:.2f} s | {times[-1]:.2f} s | {len(seen)}/{args.peers} |")
        print(f"| median | {statistics.median(firsts):.2f} s | {statistics.median(lasts):.2f} s | |")
        print(f"| max | {max(firsts):.2f} s | {max(lasts):.2f} s | |")
    finally:
        for peer in peers:
            peer.stop()


if __name__ == "__main__":
    main()
