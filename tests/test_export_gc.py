"""`bag export` of a type decoded message by message (tf2_msgs/TFMessage) leaves no decoded message in a
reference cycle: each batch is freed by reference counting as soon as it is written, not kept alive until
Python's full collection (which made those collections more than half the CPU of such an export)."""

from __future__ import annotations

import gc
from pathlib import Path

import pyarrow.parquet as pq
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from rostool.bag.export import ExportOptions, export_bag
from rostool.bag.export_many import _export_one
from rostool.bag.many import BagItem

STORE = get_typestore(Stores.ROS2_JAZZY)
TF = "tf2_msgs/msg/TFMessage"


def _tf_bag(path: Path, count: int) -> Path:
    types = STORE.types
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/tf", TF, typestore=STORE)
        for i in range(count):
            stamp = types["builtin_interfaces/msg/Time"](sec=i, nanosec=7)
            transforms = [
                types["geometry_msgs/msg/TransformStamped"](
                    header=types["std_msgs/msg/Header"](stamp=stamp, frame_id="map"),
                    child_frame_id=f"link{k}",
                    transform=types["geometry_msgs/msg/Transform"](
                        translation=types["geometry_msgs/msg/Vector3"](x=float(i), y=float(k), z=0.0),
                        rotation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                    ),
                )
                for k in range(2)
            ]
            message = types[TF](transforms=transforms)
            writer.write(connection, 1_000_000_000 + i, STORE.serialize_cdr(message, TF))
    return path


def _messages_in_cycles(export: object) -> int:
    """How many rosbags message objects the collector finds unreachable (only cycles hold them) after
    `export()` ran with automatic collection off."""
    gc.collect()
    gc.disable()
    gc.set_debug(gc.DEBUG_SAVEALL)
    try:
        export()  # type: ignore[operator]
        gc.collect()
        return sum("__msg__" in type(found).__name__ for found in gc.garbage)
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()


def test_exported_messages_are_freed_without_the_cycle_collector(tmp_path: Path) -> None:
    bag = _tf_bag(tmp_path / "tf", 3000)
    out = tmp_path / "out"
    options = ExportOptions(fmt="parquet", out=out)
    assert _messages_in_cycles(lambda: export_bag(bag, options)) == 0
    table = pq.read_table(out / "tf.parquet")
    assert table.num_rows == 3000
    assert table.column("t").to_pylist()[-1] == 1_000_000_000 + 2999


def test_one_bag_of_many_restores_the_collector_as_it_found_it(tmp_path: Path) -> None:
    bag = _tf_bag(tmp_path / "tf", 50)
    before = gc.get_threshold()
    result = _export_one(ExportOptions(fmt="parquet", out=tmp_path / "out"), False, None, BagItem(bag, "tf"))
    assert result.messages == 50
    assert gc.get_threshold() == before
    assert gc.get_freeze_count() == 0
    assert pq.read_table(tmp_path / "out" / "tf.parquet").num_rows == 50
