"""`bag reindex` of an .mcap cut in the middle of a chunk (a recorder killed while writing it) recovers
every complete message of that chunk, each one true (issue 27)."""

from __future__ import annotations

import os
import random
from pathlib import Path

import pytest

from tests.support import rostool

COUNT = 1000


def _payload(i: int) -> bytes:
    text = f"{i}:".encode() + random.Random(i).randbytes(200)  # incompressible: the chunk stays big
    return b"\x00\x01\x00\x00" + len(text).to_bytes(4, "little") + text  # CDR std_msgs/msg/String


def _write(path: Path, compression: str) -> None:
    from mcap.writer import CompressionType, Writer

    with path.open("wb") as out:
        writer = Writer(out, chunk_size=64 * 2**20, compression=CompressionType[compression])
        writer.start("ros2", "test")
        schema = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channel = writer.register_channel("/cut", "cdr", schema)
        for i in range(COUNT):
            writer.add_message(channel, 1_000 + i, _payload(i), 1_000 + i, i)
        writer.finish()


def _read(path: Path) -> list[int]:
    from mcap.reader import make_reader

    with path.open("rb") as stream:
        values = []
        for _schema, _channel, message in make_reader(stream).iter_messages():
            text = message.data[8:]
            assert message.data == _payload(int(text.split(b":")[0])), "a recovered message is not true"
            values.append(int(text.split(b":")[0]))
        return values


@pytest.mark.parametrize("compression", ["NONE", "ZSTD", "LZ4"])
def test_reindex_keeps_the_complete_messages_of_a_cut_chunk(tmp_path: Path, compression: str) -> None:
    whole = tmp_path / "whole.mcap"
    _write(whole, compression)
    data = whole.read_bytes()
    cut = data[: len(data) * 7 // 10]
    bag = tmp_path / "crashed.mcap"
    bag.write_bytes(cut)
    done = rostool(["bag", "reindex", str(bag)], dict(os.environ), timeout=60)
    assert done.returncode == 0, done.stderr
    values = _read(bag)
    if compression == "NONE":  # every message whose record is wholly on disk
        complete = max(i for i in range(COUNT) if cut.find(_payload(i)) >= 0) + 1
        assert values == list(range(complete)) and complete > COUNT // 2
    else:  # a compressed stream's cut-short tail gives what its complete blocks hold
        assert values == list(range(len(values))) and values, values[:3]
    assert f"{len(values)} messages indexed (some from a half-written last chunk)" in done.stdout
