"""Columnar decoding gives the per-message path's columns and values exactly: every topic of every bag in the
test data, and written bags of the fixed-layout types it is made for (with frame ids and joint names whose
lengths change mid-batch, so several layouts and the per-message fallback meet in one batch)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Ros2Writer
from rosbags.typesys import Stores, get_typestore

from rostool.bag.columnar import ColumnarDecoder, columns_from_messages
from rostool.bag.export_columns import TypePlan, arrow_type
from rostool.bag.reader import BagReader

TESTDATA = Path(__file__).resolve().parents[2] / "shared" / "testdata"
BAGS = [
    "ros1/example.bag",
    "ros1/example-bz2.bag",
    "ros2/talker_mcap",
    "ros2/talker_sqlite3",
    "ros2/cdr_test_mcap",
    "ros2/cdr_test_sqlite3",
    "ros2/split_mcap",
    "ros2/convert_b_mcap",
    "ros2/service_events_sqlite3",
]


def _both_ways(path: Path | str, batch: int = 1000) -> dict[str, tuple[int, int]]:
    """Each topic decoded columnar and message by message, compared batch by batch; returns per topic the
    rows decoded columnar and message by message."""
    counts: dict[str, tuple[int, int]] = {}
    with BagReader([path]) as reader:
        style = "ros1" if reader.ros_version == 1 else "ros2"
        for conn in reader.select([]):
            if conn.msgtype not in reader.resolver.store.fielddefs:
                continue
            datas = [bytes(data) for c, _t, data in reader.messages([conn]) if c.msgtype == conn.msgtype]
            if datas:  # as export does: the first message settles which definition decodes the type
                reader.deserialize(datas[0], conn)
            fielddefs = reader.resolver.store.fielddefs
            plan = TypePlan(fielddefs, style, reader.ros_version)
            columns = plan.columns(conn.msgtype)[1:]
            decoder = ColumnarDecoder(
                plan,
                conn.msgtype,
                columns,
                reader.ros_version == 2,
                lambda d, c=conn: reader.deserialize(d, c),
            )
            for start in range(0, len(datas), batch):
                part = datas[start : start + batch]
                got = decoder.decode(part)
                messages = [reader.deserialize(d, conn) for d in part]
                expected = columns_from_messages(columns, messages)
                for column, array, values in zip(columns, got, expected, strict=True):
                    want = pa.array(values, type=arrow_type(column.spec))
                    assert array.equals(want), f"{path} {conn.topic} {column.name}"
            counts[conn.topic] = (decoder.columnar_rows, decoder.fallback_rows)
    return counts


@pytest.mark.parametrize("name", BAGS)
def test_every_testdata_bag_decodes_as_the_per_message_path(name: str) -> None:
    path = TESTDATA / name
    if not path.exists():
        pytest.skip(f"{path} is missing")
    counts = _both_ways(path)
    assert counts, "no topic was compared"


def _fixed_layout_messages(store: object) -> list[tuple[str, str, list[object]]]:
    """Imu, Odometry, JointState, PoseStamped and Twist messages; frame ids and joint names change length
    partway, so one batch holds several layouts."""
    s = store.types  # type: ignore[attr-defined]
    time, header = s["builtin_interfaces/msg/Time"], s["std_msgs/msg/Header"]
    vec, quat = s["geometry_msgs/msg/Vector3"], s["geometry_msgs/msg/Quaternion"]
    point, pose = s["geometry_msgs/msg/Point"], s["geometry_msgs/msg/Pose"]
    twist = s["geometry_msgs/msg/Twist"]
    rng = np.random.default_rng(7)
    header_fields = [name for name, _ in store.fielddefs["std_msgs/msg/Header"][1]]  # type: ignore[attr-defined]

    def hdr(i: int) -> object:
        frame = "imu_link" if i < 700 else ("base" if i < 900 else "imu_link_ü")
        args = {"stamp": time(sec=1000 + i, nanosec=i * 997), "frame_id": frame}
        if "seq" in header_fields:  # ROS 1
            args["seq"] = i
        return header(**args)

    def cov() -> np.ndarray:
        return rng.normal(size=9)

    imu = [
        s["sensor_msgs/msg/Imu"](
            header=hdr(i),
            orientation=quat(x=rng.normal(), y=rng.normal(), z=rng.normal(), w=1.0),
            orientation_covariance=cov(),
            angular_velocity=vec(x=rng.normal(), y=0.5, z=-1.0),
            angular_velocity_covariance=cov(),
            linear_acceleration=vec(x=9.81, y=rng.normal(), z=0.0),
            linear_acceleration_covariance=cov(),
        )
        for i in range(1200)
    ]
    joints = [
        s["sensor_msgs/msg/JointState"](
            header=hdr(i),
            name=["shoulder", "elbow", "wrist"] if i % 500 else ["a", "bb"],
            position=rng.normal(size=3 if i % 500 else 2),
            velocity=rng.normal(size=3 if i % 500 else 2),
            effort=np.zeros(0),
        )
        for i in range(1200)
    ]
    twists = [
        twist(linear=vec(x=float(i), y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=0.1)) for i in range(300)
    ]
    poses = [
        s["geometry_msgs/msg/PoseStamped"](
            header=hdr(i),
            pose=pose(position=point(x=float(i), y=1.0, z=2.0), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0)),
        )
        for i in range(1200)
    ]
    return [
        ("/imu", "sensor_msgs/msg/Imu", imu),
        ("/joint_states", "sensor_msgs/msg/JointState", joints),
        ("/cmd_vel", "geometry_msgs/msg/Twist", twists),
        ("/pose", "geometry_msgs/msg/PoseStamped", poses),
    ]


@pytest.mark.parametrize("fmt", ["mcap", "sqlite3", "bag"])
def test_fixed_layout_types_decode_columnar_with_changing_lengths(tmp_path: Path, fmt: str) -> None:
    path = _write_fixed_bag(tmp_path, fmt)
    counts = _both_ways(path, batch=1024)
    for topic, (columnar, fallback) in counts.items():
        assert columnar >= 0.9 * (columnar + fallback), f"{topic}: {columnar} columnar, {fallback} not"


def _write_fixed_bag(tmp_path: Path, fmt: str) -> Path:
    if fmt == "bag":
        store = get_typestore(Stores.ROS1_NOETIC)
        path = tmp_path / "fixed.bag"
        with Ros1Writer(path) as writer:
            for topic, msgtype, messages in _fixed_layout_messages(store):
                conn = writer.add_connection(topic, msgtype, typestore=store)
                for i, msg in enumerate(messages):
                    writer.write(conn, 1_000 + i, store.serialize_ros1(msg, msgtype))
        return path
    store = get_typestore(Stores.ROS2_JAZZY)
    path = tmp_path / "fixed"
    plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
    with Ros2Writer(path, version=9, storage_plugin=plugin) as writer:
        for topic, msgtype, messages in _fixed_layout_messages(store):
            conn = writer.add_connection(topic, msgtype, typestore=store)
            for i, msg in enumerate(messages):
                writer.write(conn, 1_000 + i, store.serialize_cdr(msg, msgtype))
    return path


@pytest.mark.parametrize("fmt", ["mcap", "sqlite3", "bag"])
def test_export_tables_equal_rosbags_decoding_message_by_message(tmp_path: Path, fmt: str) -> None:
    """The Parquet tables (columnar; for .mcap read chunk by chunk) hold what rosbags decodes, row by row."""
    import pyarrow.parquet as pq

    from rostool.bag.export import ExportOptions, export_bag
    from rostool.bag.mcap_batches import plan

    path = _write_fixed_bag(tmp_path, fmt)
    if fmt == "mcap":  # the chunk reader serves this bag
        files = sorted(path.glob("*.mcap"))
        assert plan(files, {("/imu", "sensor_msgs/msg/Imu"): 1}) is not None
    out = tmp_path / "out"
    export_bag(path, ExportOptions(fmt="parquet", out=out, batch_rows=500))
    with BagReader([path]) as reader:
        style = "ros1" if reader.ros_version == 1 else "ros2"
        for conn in reader.select([]):
            rows = [(t, reader.deserialize(d, conn)) for _c, t, d in reader.messages([conn])]
            plan_ = TypePlan(reader.resolver.store.fielddefs, style, reader.ros_version)
            columns = plan_.columns(conn.msgtype)
            expected = [[t for t, _ in rows], *columns_from_messages(columns[1:], [m for _, m in rows])]
            table = pq.read_table(out / f"{conn.topic.strip('/')}.parquet")
            assert table.column_names == [c.name for c in columns]
            for column, values in zip(columns, expected, strict=True):
                want = pa.array(values, type=arrow_type(column.spec))
                assert table.column(column.name).combine_chunks().equals(want), f"{conn.topic} {column.name}"
