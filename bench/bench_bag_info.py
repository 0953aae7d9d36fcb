"""Benchmark `rostool bag info` against Debian's `rosbag info` on a >= 1 GB ROS 1 bag, and on an mcap.

Generates (in a temporary directory under /tmp, removed afterwards):
- big.bag: sensor_msgs/Image messages (640x480 rgb8, 921,600 bytes of pixels each) written with rosbags'
  writer in 768 KB chunks (rosbag's default), plus a 100 Hz geometry_msgs/Twist topic; >= 1 GB.
- big.mcap: the same messages written with the mcap library (ros2 profile, CDR, uncompressed chunks).
Then times each command as a user runs it (a new process each time, warm page cache, median of N runs).

Run: .venv/bin/python bench/bench_bag_info.py [--size-gb 1.1] [--runs 7]
Goals: rostool on .bag <= 0.5x Debian's time; rostool on .mcap <= 0.1 s.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WIDTH, HEIGHT = 640, 480
PIXELS = WIDTH * HEIGHT * 3


def generate_bag(path: Path, size_gb: float) -> int:
    import numpy as np
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    types = store.types
    frames = int(size_gb * 1e9 / PIXELS) + 1
    pixels = np.frombuffer(os.urandom(PIXELS), dtype=np.uint8)
    writer = Writer(path)
    writer.chunk_threshold = 768 * 1024
    count = 0
    with writer:
        camera = writer.add_connection("/camera/image_raw", "sensor_msgs/msg/Image", typestore=store)
        cmd = writer.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=store)
        vec = types["geometry_msgs/msg/Vector3"]
        twist = store.serialize_ros1(
            types["geometry_msgs/msg/Twist"](vec(1.0, 0, 0), vec(0, 0, 0.5)), "geometry_msgs/msg/Twist"
        )
        start = 1_700_000_000_000_000_000
        for i in range(frames):
            stamp = start + i * 33_333_333
            time_msg = types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
            header = types["std_msgs/msg/Header"](seq=i, stamp=time_msg, frame_id="camera")
            image = types["sensor_msgs/msg/Image"](header, HEIGHT, WIDTH, "rgb8", 0, WIDTH * 3, pixels)
            writer.write(camera, stamp, store.serialize_ros1(image, "sensor_msgs/msg/Image"))
            for k in range(3):
                writer.write(cmd, stamp + k * 10_000_000, twist)
            count += 4
    return count


def generate_mcap(path: Path, size_gb: float) -> int:
    import numpy as np
    from mcap.writer import CompressionType, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = store.types
    frames = int(size_gb * 1e9 / PIXELS) + 1
    pixels = np.frombuffer(os.urandom(PIXELS), dtype=np.uint8)
    count = 0
    with path.open("wb") as handle:
        writer = Writer(handle, compression=CompressionType.NONE)
        writer.start("ros2", "bench")
        text, _ = store.generate_msgdef("sensor_msgs/msg/Image", ros_version=2)
        schema = writer.register_schema("sensor_msgs/msg/Image", "ros2msg", text.encode())
        channel = writer.register_channel("/camera/image_raw", "cdr", schema, {"offered_qos_profiles": ""})
        start = 1_700_000_000_000_000_000
        for i in range(frames):
            stamp = start + i * 33_333_333
            time_msg = types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
            header = types["std_msgs/msg/Header"](stamp=time_msg, frame_id="camera")
            image = types["sensor_msgs/msg/Image"](header, HEIGHT, WIDTH, "rgb8", 0, WIDTH * 3, pixels)
            data = bytes(store.serialize_cdr(image, "sensor_msgs/msg/Image"))
            writer.add_message(channel, stamp, data, stamp)
            count += 1
        writer.finish()
    return count


def _report(path: Path, count: int, t0: float) -> None:
    took = time.perf_counter() - t0
    print(f"generated {path}: {path.stat().st_size / 1e9:.2f} GB, {count} msgs, {took:.0f} s")


def timed(cmd: list[str], env: dict[str, str], runs: int) -> tuple[float, str]:
    output = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout  # warm up
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(cmd, env=env, capture_output=True, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times), output


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--size-gb", type=float, default=1.1)
    parser.add_argument("--runs", type=int, default=7)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="rostool-bench-info-", dir="/tmp"))
    try:
        bag, mcap = work / "big.bag", work / "big.mcap"
        t0 = time.perf_counter()
        count = generate_bag(bag, args.size_gb)
        _report(bag, count, t0)
        t0 = time.perf_counter()
        count = generate_mcap(mcap, args.size_gb)
        _report(mcap, count, t0)

        ours_env = dict(os.environ)
        debian_env = {
            k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")
        }
        debian_env["PATH"] = "/usr/bin:/bin"
        rostool = [sys.executable, "-m", "rostool", "bag", "info"]

        ours_bag, ours_text = timed([*rostool, str(bag)], ours_env, args.runs)
        theirs_bag, theirs_text = timed(["rosbag", "info", str(bag)], debian_env, args.runs)
        same = ours_text.rstrip() == theirs_text.rstrip()
        ours_mcap, _ = timed([*rostool, str(mcap)], ours_env, args.runs)
        ours_json, _ = timed([*rostool, "--json", str(mcap)], ours_env, args.runs)
        print(f"rosbag info big.bag (Debian):    {theirs_bag:.3f} s")
        ratio = ours_bag / theirs_bag
        print(f"rostool bag info big.bag:        {ours_bag:.3f} s  ratio {ratio:.2f}x (goal <= 0.5x)")
        print(f"  same text as rosbag info:      {same}")
        print(f"rostool bag info big.mcap:       {ours_mcap:.3f} s  (goal <= 0.1 s)")
        print(f"rostool bag info --json big.mcap: {ours_json:.3f} s")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
