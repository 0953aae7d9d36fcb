"""Decoding to Arrow: columnar (rostool.bag.columnar) against rosbags' per-message deserializer feeding
the same columns, on fixed-layout types (Imu, Odometry, JointState, PoseStamped, Twist) and on one it cannot
read column-wise (TFMessage: a sequence of messages), in one process, payloads already in memory.

    .venv/bin/python bench/bench_columnar.py [N]
"""

from __future__ import annotations

import sys
import time

import numpy as np
import pyarrow as pa
from rosbags.typesys import Stores, get_typestore

from rostool.bag.columnar import ColumnarDecoder, columns_from_messages
from rostool.bag.export_columns import TypePlan, arrow_type

BATCH = 8192


def messages(store, msgtype: str, n: int) -> list[bytes]:
    s = store.types
    time_, header = s["builtin_interfaces/msg/Time"], s["std_msgs/msg/Header"]
    vec, quat = s["geometry_msgs/msg/Vector3"], s["geometry_msgs/msg/Quaternion"]
    point, pose = s["geometry_msgs/msg/Point"], s["geometry_msgs/msg/Pose"]
    rng = np.random.default_rng(1)

    def hdr(i: int) -> object:
        return header(stamp=time_(sec=i, nanosec=7), frame_id="imu_link")

    def make(i: int) -> object:
        if msgtype == "sensor_msgs/msg/Imu":
            return s[msgtype](
                header=hdr(i),
                orientation=quat(x=0.1, y=0.2, z=0.3, w=1.0),
                orientation_covariance=rng.normal(size=9),
                angular_velocity=vec(x=1.0, y=2.0, z=3.0),
                angular_velocity_covariance=rng.normal(size=9),
                linear_acceleration=vec(x=9.8, y=0.0, z=0.1),
                linear_acceleration_covariance=rng.normal(size=9),
            )
        if msgtype == "nav_msgs/msg/Odometry":
            p = s["geometry_msgs/msg/PoseWithCovariance"](
                pose=pose(
                    position=point(x=float(i), y=0.0, z=0.0), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0)
                ),
                covariance=rng.normal(size=36),
            )
            t = s["geometry_msgs/msg/TwistWithCovariance"](
                twist=s["geometry_msgs/msg/Twist"](
                    linear=vec(x=1.0, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=0.1)
                ),
                covariance=rng.normal(size=36),
            )
            return s[msgtype](header=hdr(i), child_frame_id="base_link", pose=p, twist=t)
        if msgtype == "sensor_msgs/msg/JointState":
            return s[msgtype](
                header=hdr(i),
                name=["j1", "j2", "j3", "j4", "j5", "j6"],
                position=rng.normal(size=6),
                velocity=rng.normal(size=6),
                effort=rng.normal(size=6),
            )
        if msgtype == "geometry_msgs/msg/PoseStamped":
            return s[msgtype](
                header=hdr(i),
                pose=pose(
                    position=point(x=float(i), y=0.0, z=0.0), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0)
                ),
            )
        if msgtype == "geometry_msgs/msg/Twist":
            return s[msgtype](linear=vec(x=float(i), y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=0.1))
        tf = s["geometry_msgs/msg/TransformStamped"](
            header=hdr(i),
            child_frame_id="base",
            transform=s["geometry_msgs/msg/Transform"](
                translation=vec(x=1.0, y=0.0, z=0.0), rotation=quat(x=0.0, y=0.0, z=0.0, w=1.0)
            ),
        )
        return s[msgtype](transforms=[tf, tf])

    sample = [store.serialize_cdr(make(i), msgtype) for i in range(min(n, 2000))]
    return [sample[i % len(sample)] for i in range(n)]  # same bytes repeated: decoding cost is what is timed


def run(msgtype: str, n: int) -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    datas = messages(store, msgtype, n)
    plan = TypePlan(store.fielddefs, "ros2", 2)
    columns = plan.columns(msgtype)[1:]
    types = [arrow_type(c.spec) for c in columns]

    def deserialize(d: bytes) -> object:
        return store.deserialize_cdr(d, msgtype)

    decoder = ColumnarDecoder(plan, msgtype, columns, True, deserialize)
    start = time.perf_counter()
    for i in range(0, n, BATCH):
        decoder.decode(datas[i : i + BATCH])
    columnar = time.perf_counter() - start
    m = min(n, 100_000)
    start = time.perf_counter()
    for i in range(0, m, BATCH):
        msgs = [deserialize(d) for d in datas[i : i + BATCH]]
        values = columns_from_messages(columns, msgs)
        [pa.array(v, type=t) for v, t in zip(values, types, strict=True)]
    per_message = (time.perf_counter() - start) / m * n
    start = time.perf_counter()
    for d in datas[:m]:
        deserialize(d)
    rosbags = (time.perf_counter() - start) / m * n
    print(
        f"| {msgtype} | {n:,} | {n / columnar:,.0f} | {n / per_message:,.0f} | {n / rosbags:,.0f} |"
        f" {per_message / columnar:.1f}x | {decoder.columnar_rows / n:.0%} |"
    )


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    print(
        "| type | messages | columnar msg/s | per-message msg/s | rosbags deserialize only msg/s"
        " | speed-up | rows columnar |"
    )
    print("|---|---|---|---|---|---|---|")
    for msgtype in (
        "sensor_msgs/msg/Imu",
        "nav_msgs/msg/Odometry",
        "sensor_msgs/msg/JointState",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/Twist",
        "tf2_msgs/msg/TFMessage",
    ):
        run(msgtype, n)


if __name__ == "__main__":
    main()
