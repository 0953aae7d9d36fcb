"""`rostool bag reindex`: bags whose writer was killed get every message that reached the disk back."""

from __future__ import annotations

import json
import shutil
import struct
from pathlib import Path

import yaml

from rostool.bag import ros1_format as fmt
from rostool.bag.reader import BagReader
from rostool.output.plain import to_plain
from tests.support import debian, require_ros1_peers, rostool
from tests.test_bag_support import env, shared, write_ros1_bag


def _payloads(path: Path) -> list[tuple[str, int, bytes]]:
    """(topic, time, raw bytes) of every message, read with rosbags' own reader."""
    from rosbags.rosbag1 import Reader

    with Reader(path) as reader:
        return [(c.topic, t, bytes(d)) for c, t, d in reader.messages()]


def _kill(path: Path, cut: int | None = None) -> int:
    """What a SIGKILLed recorder leaves: no index section, index_pos 0 in the header. Returns index_pos."""
    data = bytearray(path.read_bytes())
    with path.open("rb") as handle:
        index_pos = fmt.get_u64(fmt.read_file_header(handle), "index_pos")
    data = data[: index_pos if cut is None else cut]
    at = data.index(b"index_pos=") + len(b"index_pos=")
    data[at : at + 8] = bytes(8)
    path.write_bytes(bytes(data))
    return index_pos


def _reindex(path: Path) -> str:
    result = rostool(["bag", "reindex", str(path)], env())
    assert result.returncode == 0, result.stderr
    return result.stdout


def _debian_info(path: Path) -> dict[str, object]:
    require_ros1_peers()
    result = debian(["rosbag", "info", "--yaml", str(path)], env())
    assert result.returncode == 0, result.stderr
    return yaml.safe_load(result.stdout)  # type: ignore[no-any-return]


def test_killed_bag_gets_every_message_back(tmp_path: Path) -> None:
    for compression in (None, "bz2", "lz4"):
        bag = write_ros1_bag(tmp_path / f"run_{compression}.bag", compression=compression)
        original = _payloads(bag)
        _kill(bag)
        killed = bag.read_bytes()
        broken = rostool(["bag", "info", str(bag)], env())
        assert broken.returncode == 1 and "reindex" in broken.stderr
        assert "90 messages indexed" in _reindex(bag)
        assert _payloads(bag) == original
        backup = tmp_path / f"run_{compression}.orig.bag"
        assert backup.read_bytes() == killed
        info = _debian_info(bag)
        assert info["messages"] == 90 and info["compression"] == (compression or "none")
        topics = {t["topic"]: t["messages"] for t in info["topics"]}  # type: ignore[attr-defined]
        assert topics == {"/chatter": 30, "/cmd_vel": 30, "/tf": 30}
        ours = json.loads(rostool(["bag", "info", "--json", str(bag)], env()).stdout)
        assert ours["messages"] == 90


def test_half_written_chunk_keeps_complete_messages(tmp_path: Path) -> None:
    from rosbags.rosbag1 import Reader

    bag = write_ros1_bag(tmp_path / "run.bag", chunk_threshold=1 << 30)  # one uncompressed chunk
    original = _payloads(bag)
    with Reader(bag) as reader:
        chunk = next(iter(reader.chunks.values()))
        offsets = sorted(entry.offset for index in reader.indexes.values() for entry in index)
    cut = chunk.datapos + offsets[57] + 10  # in the middle of message 57's record
    _kill(bag, cut)
    assert "57 messages indexed (some from a half-written last chunk)" in _reindex(bag)
    assert _payloads(bag) == original[:57]
    assert _debian_info(bag)["messages"] == 57


def test_unterminated_chunk_as_rosbag_record_leaves_it(tmp_path: Path) -> None:
    """rosbag record writes a chunk header with size 0 and fills in the sizes when the chunk closes."""
    from rosbags.rosbag1 import Reader

    bag = write_ros1_bag(tmp_path / "run.bag", chunk_threshold=1 << 30)
    original = _payloads(bag)
    with Reader(bag) as reader:
        chunk = next(iter(reader.chunks.values()))
        offsets = sorted(entry.offset for index in reader.indexes.values() for entry in index)
    data = bytearray(bag.read_bytes())
    size_at = data.index(b"size=", 4096) + len(b"size=")
    data[size_at : size_at + 4] = bytes(4)
    data[chunk.datapos - 4 : chunk.datapos] = bytes(4)
    bag.write_bytes(bytes(data))
    _kill(bag, chunk.datapos + offsets[80] + 3)
    _reindex(bag)
    assert _payloads(bag) == original[:80]


def test_reindex_real_bag_copy_is_lossless(tmp_path: Path) -> None:
    bag = tmp_path / "example.bag"
    bag.write_bytes(shared("ros1/example-bz2.bag").read_bytes())
    _kill(bag)
    _reindex(bag)
    assert _payloads(bag) == _payloads(shared("ros1/example-bz2.bag"))
    info = _debian_info(bag)
    assert info["messages"] == 8647


def test_mcap_without_summary_gets_one(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    src = write_ros1_bag(tmp_path / "src.bag")
    full = tmp_path / "full.mcap"
    assert rostool(["bag", "convert", str(src), str(full)], env()).returncode == 0
    with full.open("rb") as handle:
        reader = make_reader(handle)
        summary = reader.get_summary()
        assert summary is not None
        data_end = min(c.chunk_start_offset + c.chunk_length for c in summary.chunk_indexes[-1:])
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(full.read_bytes()[:data_end])  # no data end, summary nor footer
    echo = rostool(["bag", "echo", str(cut)], env())
    assert echo.returncode == 1 and "reindex" in echo.stderr
    scanned = json.loads(rostool(["bag", "info", "--json", str(cut)], env()).stdout)
    assert scanned["messages"] == 90
    _reindex(cut)
    assert (tmp_path / "cut.orig.mcap").exists()
    with cut.open("rb") as handle:
        summary = make_reader(handle).get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == 90
    with BagReader([cut]) as reader, BagReader([full]) as whole:
        got = [(c.topic, t, to_plain(reader.deserialize(d, c))) for c, t, d in reader.messages()]
        want = [(c.topic, t, to_plain(whole.deserialize(d, c))) for c, t, d in whole.messages()]
    assert got == want


def test_reindex_refuses_what_it_cannot_do(tmp_path: Path) -> None:
    result = rostool(["bag", "reindex", str(shared("ros2/talker_sqlite3"))], env())
    assert result.returncode == 1 and "reindex works on" in result.stderr
    bag = write_ros1_bag(tmp_path / "a.bag")
    (tmp_path / "a.orig.bag").write_bytes(b"")
    result = rostool(["bag", "reindex", str(bag)], env())
    assert result.returncode == 1 and "a.orig.bag exists" in result.stderr
    assert struct.unpack("<I", bag.read_bytes()[13:17])[0] > 0  # untouched


def _rosbags_count(path: Path) -> tuple[int, list[str]]:
    """Messages and topics of a rosbag2 directory, read by rosbags' own reader (metadata.yaml first)."""
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return sum(1 for _ in reader.messages()), sorted(c.topic for c in reader.connections)


def test_rosbag2_directory_cut_short_gets_metadata_back(tmp_path: Path) -> None:
    """A killed recorder's NAME.db3.active/ or NAME.mcap.active/: storage without metadata.yaml (and an
    .mcap without its summary); `bag reindex DIR` writes metadata.yaml as `ros2 bag reindex` does."""
    for name in ("talker_sqlite3", "talker_mcap"):
        whole = tmp_path / name
        shutil.copytree(shared(f"ros2/{name}"), whole)
        whole.chmod(0o755)
        with BagReader([whole]) as reader:  # rosbags reads no message of these two (QoS mismatch)
            expected = reader.message_count, sorted(reader.topics)
        cut = tmp_path / f"{name}.active"
        cut.mkdir()
        (storage,) = [p for p in whole.iterdir() if p.suffix in (".db3", ".mcap")]
        data = storage.read_bytes()
        if storage.suffix == ".mcap":  # no footer: cut somewhere in the data section
            data = data[: len(data) * 6 // 10]
        (cut / storage.name).write_bytes(data)
        out = _reindex(cut)
        assert "messages indexed" in out and (tmp_path / f"{name}.active.orig" / storage.name).is_file()
        messages, topics = _rosbags_count(cut)
        assert topics == expected[1]
        if storage.suffix == ".db3":
            assert messages == expected[0]
        else:
            assert 0 < messages <= expected[0]
        again = rostool(["bag", "reindex", str(cut)], env())
        assert again.returncode == 1 and "this one is complete" in again.stderr


def test_mcap_with_a_damaged_compressed_chunk(tmp_path: Path) -> None:
    """Found by bench/atheris_fuzz.py: zstd's error from a corrupted chunk escaped reindex. The records
    before the damage are kept; the file is rebuilt and readable."""
    damaged = tmp_path / "talker.mcap"
    data = bytearray(shared("ros2/talker_mcap/talker.mcap").read_bytes())
    data[45 + 200 : 45 + 260] = bytes(60)  # inside the one zstd chunk's compressed data
    damaged.write_bytes(bytes(data))
    out = _reindex(damaged)
    assert "messages indexed" in out
    info = rostool(["bag", "info", "--json", str(damaged)], env())
    assert info.returncode == 0, info.stderr
