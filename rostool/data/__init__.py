"""rostool's Python API for bag data: one topic of a bag as a typed pyarrow Table, many bags as a Ray Dataset.

The columns are `bag export`'s (`t`, `stamp`, the fields flattened, Time as sec/nanosec, arrays as lists), for
ROS 1 .bag, rosbag2 directories, .mcap and .db3 alike:

    from rostool.data import read_bag_table, read_bags
    imu = read_bag_table("run.mcap", "/imu")                    # pyarrow.Table, no Ray needed
    ds = read_bags(["fleet/"], topics=["/odom"])                # ray.data.Dataset (rostool[ray])
    ds.filter(lambda row: row["twist.twist.linear.x"] > 1.0).groupby("bag").count().show()

(This folder also holds rostool's data files, such as the cheatsheet.)
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO

__all__ = ["read_bag_table", "read_bag_tables", "read_bags"]


def read_bag_tables(
    path: str | Path, topics: Sequence[str] = (), distro: str = DEFAULT_DISTRO
) -> dict[str, Any]:
    """Every wanted topic of one bag (all when `topics` is empty) as {topic: pyarrow.Table}."""
    from rostool.bag.export import ExportOptions, export_bag

    options = ExportOptions(fmt="arrow", out=Path("."), topics=list(topics), distro=distro)
    return export_bag(path, options).tables


def read_bag_table(path: str | Path, topic: str, distro: str = DEFAULT_DISTRO) -> Any:
    """One topic of one bag as a pyarrow.Table with `bag export`'s columns."""
    tables = read_bag_tables(path, [topic], distro)
    if topic not in tables:
        raise RostoolError(f"{path}: no topic {topic}")
    return tables[topic]


def read_bags(
    paths: Sequence[str | Path], topics: Sequence[str] | None = None, distro: str = DEFAULT_DISTRO
) -> Any:
    """Bags (files, rosbag2 directories, or directories of bags) as one ray.data.Dataset: `bag export`'s
    columns plus `bag` (the bag's name, as in an exported dataset's partitions) and `topic`; a bag is read
    by one task. Topics of different types make a dataset whose columns are their union (nulls where a
    type lacks one): choose `topics` of one type for a table of one shape. Without a connected Ray, a
    private local one is started (loopback only) and kept for the rest of the process."""
    from rostool.bag.many import expand
    from rostool.bag.ray_engine import connect

    ray = connect(None)
    items = expand(list(paths))
    rows = [{"path": str(item.path), "bag": item.name} for item in items]
    dataset = ray.data.from_items(rows, override_num_blocks=max(len(rows), 1))
    options = {"topics": tuple(topics or ()), "distro": distro}
    return dataset.map_batches(_read_batch, fn_kwargs=options, batch_size=1, batch_format="pyarrow")


def _read_batch(batch: Any, topics: tuple[str, ...], distro: str) -> Any:
    """One Ray task's work: bags' paths -> their topics' rows, with `bag` and `topic` columns."""
    import pyarrow as pa

    from rostool.bag.export_many import fewer_collections

    tables = []
    for path, bag in zip(batch.column("path").to_pylist(), batch.column("bag").to_pylist(), strict=True):
        with fewer_collections():
            read = read_bag_tables(path, topics, distro)
        for topic, table in read.items():
            table = table.append_column("bag", pa.array([bag] * table.num_rows, pa.string()))
            tables.append(table.append_column("topic", pa.array([topic] * table.num_rows, pa.string())))
    if not tables:
        return pa.table({"bag": pa.array([], pa.string()), "topic": pa.array([], pa.string())})
    return pa.concat_tables(tables, promote_options="permissive")
