"""`bag export`: topics whose names differ only in `/` and `.` (or other characters) get distinct files, and
every row lands in its own topic's file (issue 27)."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

from tests.support import rostool

TOPICS = {"/a/b": "a.b", "/a.b": "a%2Eb", "/a b": "a%20b", "/a%2Eb": "a%252Eb", "/x-y": "x-y"}


def _bag(path: Path) -> Path:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    string = store.types["std_msgs/msg/String"]
    with Writer(path) as writer:
        for n, topic in enumerate(TOPICS):
            conn = writer.add_connection(topic, "std_msgs/msg/String", typestore=store)
            for i in range(3 + n):
                data = store.serialize_ros1(string(data=f"{topic}#{i}"), "std_msgs/msg/String")
                writer.write(conn, 1_700_000_000_000_000_000 + n * 1000 + i, data)
    return path


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_colliding_topic_names_get_their_own_files(tmp_path: Path, fmt: str) -> None:
    if fmt == "parquet":
        pytest.importorskip("pyarrow.parquet")
    bag = _bag(tmp_path / "names.bag")
    out = tmp_path / "out"
    done = rostool(["bag", "export", str(bag), "--format", fmt, "-o", str(out)], dict(os.environ), timeout=60)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in out.iterdir()) == sorted(f"{name}.{fmt}" for name in TOPICS.values())
    for n, (topic, name) in enumerate(TOPICS.items()):
        if fmt == "csv":
            with (out / f"{name}.csv").open(newline="") as handle:
                values = [row["data"] for row in csv.DictReader(handle)]
        else:
            import pyarrow.parquet as pq

            values = pq.read_table(out / f"{name}.parquet").column("data").to_pylist()
        assert values == [f"{topic}#{i}" for i in range(3 + n)]
