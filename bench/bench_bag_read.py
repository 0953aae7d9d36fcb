"""Read throughput of rostool's BagReader against rosbags' AnyReader alone (read + deserialize every message).

Generates in a temporary directory under /tmp (removed afterwards), with rosbags' writers:
- small.bag: 200,000 small messages (std_msgs/String, geometry_msgs/Twist, tf2_msgs/TFMessage);
- images.bag: 300 sensor_msgs/Image (640x480 rgb8) plus 3,000 Twist;
- small.mcap / small.db3 / images.mcap: the same converted by `rostool bag convert` (rosbag2 storage).
Each reader runs 3 times per bag in this process; the best time counts.

Run: .venv/bin/python bench/bench_bag_read.py
Goal: rostool's throughput >= 1.0x AnyReader's.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path


def generate(work: Path) -> dict[str, Path]:
    import numpy as np
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(
        get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
    )
    t = store.types
    vec = t["geometry_msgs/msg/Vector3"]
    start = 1_700_000_000_000_000_000

    def stamp_header(i: int, stamp: int) -> object:
        time_msg = t["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
        return t["std_msgs/msg/Header"](seq=i, stamp=time_msg, frame_id="map")

    small = work / "small.bag"
    with Writer(small) as writer:
        chatter = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        cmd = writer.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=store)
        tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
        for i in range(200_000):
            stamp = start + i * 1_000_000
            if i % 3 == 0:
                data = store.serialize_ros1(
                    t["std_msgs/msg/String"](data=f"hello {i}"), "std_msgs/msg/String"
                )
                writer.write(chatter, stamp, data)
            elif i % 3 == 1:
                msg = t["geometry_msgs/msg/Twist"](vec(i, 0, 0), vec(0, 0, 1))
                writer.write(cmd, stamp, store.serialize_ros1(msg, "geometry_msgs/msg/Twist"))
            else:
                transform = t["geometry_msgs/msg/Transform"](
                    vec(i, 1, 2), t["geometry_msgs/msg/Quaternion"](0, 0, 0, 1)
                )
                stamped = t["geometry_msgs/msg/TransformStamped"](stamp_header(i, stamp), "base", transform)
                msg = t["tf2_msgs/msg/TFMessage"](transforms=[stamped])
                writer.write(tf, stamp, store.serialize_ros1(msg, "tf2_msgs/msg/TFMessage"))

    images = work / "images.bag"
    pixels = np.arange(640 * 480 * 3, dtype=np.uint32).astype(np.uint8)
    with Writer(images) as writer:
        camera = writer.add_connection("/camera/image_raw", "sensor_msgs/msg/Image", typestore=store)
        cmd = writer.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=store)
        twist = store.serialize_ros1(
            t["geometry_msgs/msg/Twist"](vec(1, 0, 0), vec(0, 0, 1)), "geometry_msgs/msg/Twist"
        )
        for i in range(300):
            stamp = start + i * 33_000_000
            image = t["sensor_msgs/msg/Image"](stamp_header(i, stamp), 480, 640, "rgb8", 0, 1920, pixels)
            writer.write(camera, stamp, store.serialize_ros1(image, "sensor_msgs/msg/Image"))
            for k in range(10):
                writer.write(cmd, stamp + k * 3_000_000, twist)

    bags = {"small.bag": small, "images.bag": images}
    for src, dst in (("small.bag", "small.mcap"), ("small.bag", "small.db3"), ("images.bag", "images.mcap")):
        subprocess.run(
            [sys.executable, "-m", "rostool", "bag", "convert", str(work / src), str(work / dst)], check=True
        )
        bags[dst] = work / dst
    return bags


def read_ours(path: Path) -> tuple[int, int]:
    from rostool.bag.reader import BagReader

    count = size = 0
    with BagReader([path]) as reader:
        for conn, _t, data in reader.messages():
            reader.deserialize(data, conn)
            count += 1
            size += len(data)
    return count, size


def read_anyreader(path: Path) -> tuple[int, int]:
    from rosbags.highlevel import AnyReader

    count = size = 0
    with AnyReader([path]) as reader:
        for conn, _t, data in reader.messages():
            reader.deserialize(data, conn.msgtype)
            count += 1
            size += len(data)
    return count, size


def best(func: Callable[[Path], tuple[int, int]], path: Path) -> tuple[float, int, int]:
    times = []
    for _ in range(3):
        start = time.perf_counter()
        count, size = func(path)
        times.append(time.perf_counter() - start)
    return min(times), count, size


def main() -> None:
    work = Path(tempfile.mkdtemp(prefix="rostool-bench-read-", dir="/tmp"))
    try:
        bags = generate(work)
        print(f"{'bag':<12} {'msgs':>7} {'MB':>7} | {'AnyReader MB/s':>14} {'msgs/s':>9} | "
              f"{'rostool MB/s':>12} {'msgs/s':>9} | ratio")  # fmt: skip
        ratios = []
        for name, path in bags.items():
            theirs, count, size = best(read_anyreader, path)
            ours, our_count, our_size = best(read_ours, path)
            assert (our_count, our_size) == (count, size), name
            ratio = theirs / ours
            ratios.append(ratio)
            mb = size / 1e6
            print(f"{name:<12} {count:>7} {mb:>7.1f} | {mb / theirs:>14.1f} {count / theirs:>9.0f} | "
                  f"{mb / ours:>12.1f} {count / ours:>9.0f} | {ratio:.2f}x")  # fmt: skip
        print(f"lowest ratio (rostool throughput / AnyReader throughput): {min(ratios):.2f}x (goal >= 1.0x)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
