"""Helpers for the bag tests: the shared bags, independent counting with rosbags, small generated bags."""

from __future__ import annotations

import os
import shutil
from collections import Counter
from pathlib import Path

from tests.support import TESTDATA

ROS1_BAGS = ["ros1/example.bag", "ros1/example-bz2.bag", "ros1/no-messages.bag"]
ROS2_BAGS = [
    "ros2/cdr_test_mcap",
    "ros2/cdr_test_sqlite3",
    "ros2/convert_b_mcap",
    "ros2/empty_bag_sqlite3",
    "ros2/service_events_sqlite3",
    "ros2/split_mcap",
    "ros2/talker_mcap",
    "ros2/talker_sqlite3",
    "ros2/talker_mcap/talker.mcap",
    "ros2/talker_sqlite3/talker.db3",
    "ros2/cdr_test_sqlite3/cdr_test_0.db3",
]
ALL_BAGS = ROS1_BAGS + ROS2_BAGS


def shared(name: str) -> Path:
    return TESTDATA / name


def env() -> dict[str, str]:
    return dict(os.environ)


def true_counts(path: Path) -> Counter[str]:
    """Messages per topic, counted by iterating rosbags' own per-file readers (not ours)."""
    from rosbags.rosbag1 import Reader as Reader1
    from rosbags.rosbag2 import Reader as Reader2

    files = [path]
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix in (".mcap", ".db3"))
    counts: Counter[str] = Counter()
    for file in files:
        reader_class = Reader1 if file.suffix == ".bag" else Reader2
        with reader_class(file) as reader:
            for conn, _t, _data in reader.messages():
                counts[conn.topic] += 1
    return counts


def copy_shared(name: str, into: Path) -> Path:
    """A writable copy of a shared bag (file or directory)."""
    src = shared(name)
    dst = into / src.name
    if src.is_dir():
        shutil.copytree(src, dst)
        for file in dst.rglob("*"):
            file.chmod(0o644)
        dst.chmod(0o755)
    else:
        shutil.copyfile(src, dst)
        dst.chmod(0o644)
    return dst


def write_ros1_bag(
    path: Path, count: int = 90, chunk_threshold: int = 4000, compression: str | None = None
) -> Path:
    """A small ROS 1 bag written with rosbags' writer: String, Twist and TF messages in several chunks."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(
        get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
    )
    types = store.types
    writer = Writer(path)
    writer.chunk_threshold = chunk_threshold
    if compression:
        writer.set_compression(Writer.CompressionFormat[compression.upper()])
    with writer:
        chatter = writer.add_connection(
            "/chatter", "std_msgs/msg/String", typestore=store, callerid="/talker"
        )
        twist = writer.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=store)
        tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store, latching=1)
        vec = types["geometry_msgs/msg/Vector3"]
        for i in range(count):
            stamp = 1_700_000_000_000_000_000 + i * 10_000_000
            kind = i % 3
            if kind == 0:
                msg = types["std_msgs/msg/String"](data=f"hello {i}")
                writer.write(chatter, stamp, store.serialize_ros1(msg, "std_msgs/msg/String"))
            elif kind == 1:
                msg = types["geometry_msgs/msg/Twist"](
                    linear=vec(x=i * 0.5, y=-1.0, z=0.0), angular=vec(0.0, 0.0, i)
                )
                writer.write(twist, stamp, store.serialize_ros1(msg, "geometry_msgs/msg/Twist"))
            else:
                time = types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
                header = types["std_msgs/msg/Header"](seq=i, stamp=time, frame_id="world")
                transform = types["geometry_msgs/msg/Transform"](
                    translation=vec(x=float(i), y=2.0, z=3.0),
                    rotation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                )
                stamped = types["geometry_msgs/msg/TransformStamped"](
                    header=header, child_frame_id=f"robot{i}", transform=transform
                )
                msg = types["tf2_msgs/msg/TFMessage"](transforms=[stamped])
                writer.write(tf, stamp, store.serialize_ros1(msg, "tf2_msgs/msg/TFMessage"))
    return path
