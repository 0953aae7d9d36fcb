"""`bag export` of a big .mcap cut into runs of chunks exported in parallel worker processes and joined
byte-wise (bag/parquet_concat.py): the tables equal one export's, as pyarrow and the mcap library read them;
a bag whose piece fails leaves nothing behind."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

from rostool.bag import export_cost
from rostool.bag.export import ExportOptions, export_bag
from rostool.bag.export_many import export_bags, plan
from rostool.bag.many import expand
from rostool.bag.parquet_concat import concat
from rostool.errors import RostoolError

STORE = get_typestore(Stores.ROS2_JAZZY)
IMU, TEXT = "sensor_msgs/msg/Imu", "std_msgs/msg/String"


def _bag(path: Path, count: int = 6000, chunk_size: int = 16 * 1024) -> Path:
    """An indexed .mcap of Imu and String messages (String lengths vary) in many small zstd chunks."""
    types = STORE.types
    rng = np.random.default_rng(7)
    with path.open("wb") as stream:
        writer = Writer(stream, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        writer.start("ros2", "rostool-test")
        channels = {}
        for topic, msgtype in (("/imu", IMU), ("/chatter", TEXT), ("/silent", TEXT)):
            text = STORE.generate_msgdef(msgtype, ros_version=2)[0]
            schema = writer.register_schema(msgtype, "ros2msg", text.encode())
            channels[topic] = writer.register_channel(topic, "cdr", schema)
        for i in range(count):
            stamp = types["builtin_interfaces/msg/Time"](sec=i, nanosec=i % 1000)
            header = types["std_msgs/msg/Header"](stamp=stamp, frame_id="imu_link")
            vec = types["geometry_msgs/msg/Vector3"](x=float(i), y=rng.normal(), z=-1.0)
            quat = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
            imu = types[IMU](
                header=header, orientation=quat, orientation_covariance=rng.normal(size=9),
                angular_velocity=vec, angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec, linear_acceleration_covariance=np.ones(9),
            )  # fmt: skip
            when = 1_000_000_000 + i * 1_000_000
            writer.add_message(channels["/imu"], when, STORE.serialize_cdr(imu, IMU), when, i)
            if i % 3 == 0:
                chatter = types[TEXT](data="x" * (i % 17))
                writer.add_message(channels["/chatter"], when, STORE.serialize_cdr(chatter, TEXT), when, i)
        writer.finish()
    return path


def _export(bags: list[Path], out: Path, jobs: int, piece_bytes: int, keep_going: bool = False) -> int:
    options = ExportOptions(fmt="parquet", out=out, row_group_rows=1000)  # several row groups per piece
    out.mkdir()
    return export_bags(expand(bags), options, None, jobs, keep_going, None, piece_bytes)[0].messages


def _files(out: Path) -> list[str]:
    return sorted(str(path.relative_to(out)) for path in out.rglob("*") if path.is_file())


def test_a_bag_cut_in_pieces_exports_the_tables_one_export_writes(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "big.mcap")
    with bag.open("rb") as handle:
        summary = make_reader(handle).get_summary()
    assert summary is not None and len(summary.chunk_indexes) > 20
    whole = _export([bag], tmp_path / "whole", jobs=1, piece_bytes=1)
    cut = _export([bag], tmp_path / "cut", jobs=3, piece_bytes=1)  # three worker processes, three pieces
    assert whole == cut == 8000
    assert _files(tmp_path / "whole") == _files(tmp_path / "cut") == [
        "chatter.parquet", "imu.parquet", "silent.parquet",
    ]  # fmt: skip
    for name in ("chatter", "imu", "silent"):
        one, joined = (pq.read_table(tmp_path / where / f"{name}.parquet") for where in ("whole", "cut"))
        assert one.equals(joined)
    joined_imu = pq.read_table(tmp_path / "cut" / "imu.parquet")
    # against the mcap library's reading of the same bag: every log time, in order
    with bag.open("rb") as handle:
        times = [m.log_time for _s, c, m in make_reader(handle).iter_messages() if c.topic == "/imu"]
    assert joined_imu.column(0).to_pylist() == times
    assert joined_imu.column("linear_acceleration.x").to_pylist() == [float(i) for i in range(6000)]
    assert pq.ParquetFile(tmp_path / "cut" / "imu.parquet").num_row_groups > 3
    assert pq.read_table(tmp_path / "cut" / "silent.parquet").num_rows == 0


def test_a_cut_bag_among_several_keeps_the_hive_layout(tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    _bag(fleet / "a.mcap")
    _bag(fleet / "b.mcap", count=300, chunk_size=1 << 20)  # one chunk: not cut
    _export([fleet], tmp_path / "whole", jobs=1, piece_bytes=1)
    _export([fleet], tmp_path / "cut", jobs=2, piece_bytes=1)
    assert _files(tmp_path / "whole") == _files(tmp_path / "cut")
    assert "imu/bag=a/part-0.parquet" in _files(tmp_path / "cut")
    for where in ("whole", "cut"):
        rows = ds.dataset(tmp_path / where / "imu", partitioning="hive").to_table()
        assert sorted(rows.column("bag").unique().to_pylist()) == ["a", "b"]
    one, joined = (
        ds.dataset(tmp_path / where / "imu", partitioning="hive").to_table() for where in ("whole", "cut")
    )
    order = [(one.schema.names[0], "ascending"), ("bag", "ascending")]  # time, then bag
    assert one.sort_by(order).equals(joined.sort_by(order))


def _break_last_chunk(bag: Path) -> None:
    with bag.open("rb") as handle:
        summary = make_reader(handle).get_summary()
    assert summary is not None
    last = max(index.chunk_start_offset for index in summary.chunk_indexes)
    with bag.open("r+b") as handle:
        handle.seek(last)
        handle.write(b"\x00")  # no longer a Chunk record where the index points


def test_a_failed_piece_leaves_no_table_and_no_piece_behind(tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    _break_last_chunk(_bag(fleet / "broken.mcap"))
    _bag(fleet / "good.mcap", count=600)
    with pytest.raises(RostoolError, match=r"broken\.mcap"):
        _export([fleet / "broken.mcap"], tmp_path / "alone", jobs=2, piece_bytes=1)
    assert _files(tmp_path / "alone") == []
    with pytest.raises(RostoolError, match="1 of 2 bags failed"):  # the other bag exported all the same
        _export([fleet], tmp_path / "out", jobs=2, piece_bytes=1, keep_going=True)
    assert all("bag=good" in name for name in _files(tmp_path / "out")), _files(tmp_path / "out")
    assert pq.read_table(tmp_path / "out" / "imu" / "bag=good" / "part-0.parquet").num_rows == 600


def test_join_refuses_files_of_other_schemas(tmp_path: Path) -> None:
    pq.write_table(pa.table({"a": [1, 2]}), tmp_path / "one.parquet")
    pq.write_table(pa.table({"a": ["x"]}), tmp_path / "two.parquet")
    with pytest.raises(RostoolError, match="schemas differ"):
        concat([tmp_path / "one.parquet", tmp_path / "two.parquet"], tmp_path / "both.parquet")
    shutil.copy(tmp_path / "one.parquet", tmp_path / "three.parquet")
    concat([tmp_path / "one.parquet", tmp_path / "three.parquet"], tmp_path / "both.parquet")
    assert pq.read_table(tmp_path / "both.parquet").column("a").to_pylist() == [1, 2, 1, 2]


def test_batches_gather_into_row_groups_within_the_budget(tmp_path: Path) -> None:
    """A chunk's few dozen messages are a batch; Parquet gets row groups of many batches (up to the rows or
    bytes of a group, and early when the export's tables hold more than `held_bytes`): same table."""
    bag = _bag(tmp_path / "small-chunks.mcap")
    shapes = {
        "gathered": {},  # defaults: the whole topic is one row group
        "by-rows": {"row_group_rows": 2500},
        "by-bytes": {"row_group_bytes": 200_000},
        "per-batch": {"held_bytes": 1},  # over the budget at once: every batch written as it comes
    }
    tables = {}
    for name, settings in shapes.items():
        out = tmp_path / name
        export_bag(bag, ExportOptions(fmt="parquet", out=out, **settings))
        tables[name] = pq.ParquetFile(out / "imu.parquet")
    groups = {name: [file.metadata.row_group(i).num_rows for i in range(file.num_row_groups)]
              for name, file in tables.items()}  # fmt: skip
    assert groups["gathered"] == [6000]
    assert groups["by-rows"] == [2500, 2500, 1000]
    assert len(groups["per-batch"]) > 100  # a chunk of 16 KiB holds ~45 Imu
    assert 3 < len(groups["by-bytes"]) < len(groups["per-batch"])
    whole = tables["gathered"].read()
    assert all(file.read().equals(whole) for file in tables.values())
    with bag.open("rb") as handle:  # against the mcap library's reading of the same bag
        times = [m.log_time for _s, c, m in make_reader(handle).iter_messages() if c.topic == "/imu"]
    assert whole.column(0).to_pylist() == times
    assert whole.column("linear_acceleration.x").to_pylist() == [float(i) for i in range(6000)]


def _tf_bag(path: Path, count: int, chunk_size: int = 1 << 20) -> Path:
    """An indexed .mcap of tf2_msgs/TFMessage (a sequence of messages: decoded one by one)."""
    types = STORE.types
    with path.open("wb") as stream:
        writer = Writer(stream, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        writer.start("ros2", "rostool-test")
        text = STORE.generate_msgdef(TF, ros_version=2)[0]
        channel = writer.register_channel("/tf", "cdr", writer.register_schema(TF, "ros2msg", text.encode()))
        vec = types["geometry_msgs/msg/Vector3"](x=1.0, y=2.0, z=3.0)
        quat = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
        for i in range(count):
            header = types["std_msgs/msg/Header"](
                stamp=types["builtin_interfaces/msg/Time"](sec=i, nanosec=0), frame_id="map"
            )
            transform = types["geometry_msgs/msg/TransformStamped"](
                header=header, child_frame_id="base", transform=types["geometry_msgs/msg/Transform"](
                    translation=vec, rotation=quat),
            )  # fmt: skip
            data = STORE.serialize_cdr(types[TF](transforms=[transform]), TF)
            writer.add_message(channel, 1_000_000_000 + i, data, 1_000_000_000 + i, i)
        writer.finish()
    return path


TF = "tf2_msgs/msg/TFMessage"


def test_flat_types_are_told_from_types_with_sequences_of_messages() -> None:
    def flat(msgtype: str) -> bool:
        return export_cost.is_flat("ros2msg", STORE.generate_msgdef(msgtype, ros_version=2)[0].encode())

    assert flat(IMU) and flat(TEXT) and flat("sensor_msgs/msg/JointState") and flat("nav_msgs/msg/Odometry")
    assert not flat(TF) and not flat("visualization_msgs/msg/MarkerArray")
    assert not export_cost.is_flat("ros2idl", b"module x {};")


def test_a_bag_is_cut_where_its_decoding_costs_enough(tmp_path: Path) -> None:
    """The cost rule (export_cost.py): a bag of messages decoded one by one is cut in as many pieces as
    workers once its share holds PIECE_SECONDS; a cheap column-wise bag of the same count is not; several
    bags of equal cost are spread whole; only wanted topics count."""
    per_piece = int(export_cost.PIECE_SECONDS / export_cost.NESTED_MESSAGE)
    tf = _tf_bag(tmp_path / "tf.mcap", 2 * per_piece + 100)
    imu = _bag(tmp_path / "imu.mcap", count=600)
    assert export_cost.seconds(tf) > 100 * export_cost.seconds(imu) > 0

    def pieces(bags: list[Path], jobs: int | None = 2, **settings: object) -> list[int]:
        options = ExportOptions(**{"fmt": "parquet", "out": tmp_path / "out", **settings})  # type: ignore[arg-type]
        return [item.pieces for item in plan(expand(bags), options, None, jobs, False)[1]]

    assert pieces([tf]) == [2, 2]
    assert pieces([tf], jobs=3) == [2, 2]  # three workers, but not 3 x PIECE_SECONDS of work
    assert pieces([imu]) == [1]
    assert pieces([tf, imu]) == [2, 2, 1]
    options = ExportOptions(fmt="parquet", out=tmp_path / "out")
    order = plan(expand([imu, tf]), options, None, 2, False)[1]  # the costliest first, pieces in order
    assert [(item.name, item.piece) for item in order] == [("tf", 0), ("tf", 1), ("imu", 0)]
    assert [item.name for item in plan(expand([imu, tf]), options, None, 1, False)[1]] == ["imu", "tf"]
    copies = []
    for name in "abcd":
        copies.append(tmp_path / f"{name}.mcap")
        shutil.copy(tf, copies[-1])
    assert pieces(copies) == [1, 1, 1, 1]  # four bags of equal weight on two workers: none cut
    assert pieces([tf], topics=["/other"]) == [1]
    assert pieces([tf], fmt="csv") == [1]
    assert plan(expand([tf]), ExportOptions(fmt="parquet", out=tmp_path), None, None, False)[0] is not None
    assert plan(expand([imu]), ExportOptions(fmt="parquet", out=tmp_path), None, None, False)[0] is None


def test_a_bag_of_messages_decoded_one_by_one_cut_in_pieces_exports_the_same_table(tmp_path: Path) -> None:
    bag = _tf_bag(tmp_path / "tf.mcap", 3000, chunk_size=16 * 1024)
    whole = _export([bag], tmp_path / "whole", jobs=1, piece_bytes=1)
    cut = _export([bag], tmp_path / "cut", jobs=2, piece_bytes=1)
    assert whole == cut == 3000
    one, joined = (pq.read_table(tmp_path / where / "tf.parquet") for where in ("whole", "cut"))
    assert one.equals(joined)
    with bag.open("rb") as handle:  # against the mcap library and rosbags' deserializer
        decoded = [STORE.deserialize_cdr(m.data, TF) for _s, _c, m in make_reader(handle).iter_messages()]
    assert joined.column(0).to_pylist() == [1_000_000_000 + i for i in range(3000)]
    assert [row[0]["header"]["stamp"]["sec"] for row in joined.column("transforms").to_pylist()] == [
        msg.transforms[0].header.stamp.sec for msg in decoded
    ]


def test_a_bag_is_cut_by_its_work_not_its_bytes(tmp_path: Path) -> None:
    """Cheap Imu messages fill the first half of the file and costly TFMessage the second: pieces of equal
    bytes would give one worker nearly all the work, so chunks are weighed by their messages (counted from
    their message indexes) at export_cost's rates. The tables still equal one export's."""
    from rostool.bag.mcap_batches import ChunkPlan
    from rostool.bag.mcap_batches import plan as chunk_plan

    bag = tmp_path / "uneven.mcap"
    imu_bag, tf_bag = _bag(tmp_path / "imu.mcap", count=3000), _tf_bag(tmp_path / "tf.mcap", 3000)
    with bag.open("wb") as stream:  # the Imu bag's messages, then the TF bag's, in chunks of 16 KiB
        writer = Writer(stream, chunk_size=16 * 1024, compression=CompressionType.ZSTD)
        writer.start("ros2", "rostool-test")
        ids: dict[tuple[Path, int], int] = {}
        for source, offset in ((imu_bag, 0), (tf_bag, 10_000_000_000)):
            with source.open("rb") as handle:
                for schema, channel, message in make_reader(handle).iter_messages():
                    if (source, channel.id) not in ids:
                        schema_id = writer.register_schema(schema.name, schema.encoding, schema.data)
                        ids[source, channel.id] = writer.register_channel(channel.topic, "cdr", schema_id)
                    when = message.log_time + offset
                    writer.add_message(ids[source, channel.id], when, message.data, when, message.sequence)
        writer.finish()
    with bag.open("rb") as handle:
        summary = make_reader(handle).get_summary()
    assert summary is not None and summary.statistics is not None
    wanted = {(channel.topic, summary.schemas[channel.schema_id].name): channel.topic
              for channel in summary.channels.values()}  # fmt: skip
    chunks = chunk_plan([bag], wanted)
    assert chunks is not None and len(chunks.weights) == len(chunks.chunks) > 20
    first, second = chunks.share(0, 2), chunks.share(1, 2)
    assert first.chunks + second.chunks == chunks.chunks
    heaviest = max(chunks.weights)
    assert abs(sum(first.weights) - sum(second.weights)) <= heaviest  # equal work, to one chunk
    by_bytes = ChunkPlan(chunks.chunks, chunks.channels).share(0, 2)  # what equal bytes would have given
    assert sum(chunks.weights[: len(by_bytes.chunks)]) < sum(chunks.weights) / 3
    # the counts read off the message indexes are the writer's own statistics
    tf_channel = next(c.id for c in summary.channels.values() if c.topic == "/tf")
    tf_seconds = summary.statistics.channel_message_counts[tf_channel] * export_cost.NESTED_MESSAGE
    assert tf_seconds < sum(chunks.weights) < tf_seconds * 1.2
    whole = _export([bag], tmp_path / "whole", jobs=1, piece_bytes=1)
    cut = _export([bag], tmp_path / "cut", jobs=2, piece_bytes=1)
    assert whole == cut == 3000 + 1000 + 3000
    for table in ("imu", "chatter", "tf"):
        one, joined = (pq.read_table(tmp_path / where / f"{table}.parquet") for where in ("whole", "cut"))
        assert one.equals(joined), table


@pytest.mark.parametrize("content", [b"garbage", b"\x89MCAP0\r\n", b"\x89MCAP0\r\n" + b"\x01" * 40])
def test_a_damaged_mcap_is_one_line_not_an_internal_error(tmp_path: Path, content: bytes) -> None:
    """The cost estimate reads the summary of every .mcap before the export: a file too short for even the
    magic (the mcap library's struct.error) must leave the error to the export's own one line."""
    from tests.support import ros2_env, rostool

    bag = tmp_path / "damaged.mcap"
    bag.write_bytes(content)
    assert export_cost.seconds(bag) >= 0.0
    for jobs in ("1", "2"):
        out = tmp_path / f"out{jobs}"
        done = rostool(["bag", "export", str(bag), "-o", str(out), "-j", jobs], ros2_env())
        assert done.returncode == 1, (done.returncode, done.stderr)
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and "damaged.mcap" in lines[0] and "internal error" not in lines[0], lines
