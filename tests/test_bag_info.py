"""`rostool bag info` against independent counts (rosbags' own readers) and Debian's `rosbag info`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from tests.support import debian, require_ros1_peers, rostool
from tests.test_bag_support import ALL_BAGS, ROS1_BAGS, env, shared, true_counts, write_ros1_bag


@pytest.mark.parametrize("name", ALL_BAGS)
def test_info_counts_match_true_counts(name: str) -> None:
    path = shared(name)
    result = rostool(["bag", "info", str(path), "--json"], env())
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    expected = true_counts(path)
    assert info["messages"] == sum(expected.values())
    assert {t["name"]: t["count"] for t in info["topics"] if t["count"]} == dict(expected)
    assert info["path"] == str(path)
    assert info["size"] > 0 and isinstance(info["size"], int)
    assert info["format"] in ("bag", "rosbag2", "mcap", "db3")
    if info["messages"]:
        assert info["start"] <= info["end"]
        assert info["duration"] == pytest.approx(info["end"] - info["start"], abs=1e-6)


@pytest.mark.parametrize("name", ROS1_BAGS)
def test_info_yaml_matches_debian_rosbag_info(name: str) -> None:
    require_ros1_peers()
    path = shared(name)
    theirs = debian(["rosbag", "info", "--yaml", str(path)], env())
    assert theirs.returncode == 0, theirs.stderr
    ours = rostool(["bag", "info", "--yaml", str(path)], env())
    assert ours.returncode == 0, ours.stderr
    expected, got = yaml.safe_load(theirs.stdout), yaml.safe_load(ours.stdout)
    assert got == expected


@pytest.mark.parametrize("name", ["ros1/example.bag", "ros1/example-bz2.bag"])
def test_info_text_is_rosbag_info_text(name: str) -> None:
    require_ros1_peers()
    path = shared(name)
    theirs = debian(["rosbag", "info", str(path)], env())
    ours = rostool(["bag", "info", str(path)], env())
    assert ours.returncode == 0, ours.stderr
    assert ours.stdout.rstrip("\n") == theirs.stdout.rstrip("\n")


def test_info_freq_matches_debian(tmp_path: Path) -> None:
    require_ros1_peers()
    path = shared("ros1/example.bag")
    theirs = yaml.safe_load(debian(["rosbag", "info", "--yaml", "--freq", str(path)], env()).stdout)
    ours = json.loads(rostool(["bag", "info", "--json", "--freq", str(path)], env()).stdout)
    expected = {t["topic"]: t.get("frequency") for t in theirs["topics"]}
    got = {t["name"]: t.get("frequency") for t in ours["topics"]}
    assert got.keys() == expected.keys()
    for topic, freq in expected.items():
        assert (got[topic] is None) == (freq is None), topic
        if freq is not None:
            assert got[topic] == pytest.approx(freq, rel=1e-3), topic


def test_info_types_and_hashes() -> None:
    ros1 = json.loads(rostool(["bag", "info", "--json", str(shared("ros1/example.bag"))], env()).stdout)
    assert {"name": "turtlesim/Pose", "hash": "863b248d5016ca62ea2e895ae5265cf9"} in ros1["types"]
    rosout = next(t for t in ros1["topics"] if t["name"] == "/rosout")
    assert rosout == {"name": "/rosout", "type": "rosgraph_msgs/Log", "count": 10, "connections": 3}
    ros2 = json.loads(
        rostool(["bag", "info", "--json", str(shared("ros2/service_events_sqlite3"))], env()).stdout
    )
    event = next(t for t in ros2["types"] if t["name"] == "test_msgs/srv/BasicTypes_Event")
    assert event["hash"].startswith("RIHS01_5b9988a4")
    assert ros2["storage"] == "sqlite3" and ros2["format"] == "rosbag2"


def test_info_several_bags_is_a_json_list() -> None:
    paths = [str(shared("ros1/example.bag")), str(shared("ros2/split_mcap"))]
    result = rostool(["bag", "info", "--json", *paths], env())
    data = json.loads(result.stdout)
    assert [d["messages"] for d in data] == [8647, 6074]
    assert data[1]["files"] == [f"wbag_{i}.mcap" for i in range(5)]


def test_info_mcap_compression_and_summary() -> None:
    data = json.loads(
        rostool(["bag", "info", "--json", str(shared("ros2/talker_mcap/talker.mcap"))], env()).stdout
    )
    assert data["format"] == "mcap" and data["compression"].startswith("zstd [1/1 chunks")
    assert data["start"] == pytest.approx(1585866235.112411371)


def test_info_human_text_for_ros2() -> None:
    """A rosbag2 bag's text is `ros2 bag info`'s layout (tests/test_ros2bag_forms.py has every line)."""
    result = rostool(["bag", "info", str(shared("ros2/talker_sqlite3"))], env())
    lines = result.stdout.splitlines()
    assert lines[1].split() == ["Files:", "talker.db3"] or lines[1].startswith("Files:")
    assert "Storage id:        sqlite3" in lines
    assert any(
        line.endswith("Topic: /topic | Type: std_msgs/msg/String | Count: 10 | Serialization Format: cdr")
        for line in lines
    )


def _one_line_error(args: list[str]) -> str:
    result = rostool(args, env())
    assert result.returncode != 0
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rostool: ")
    return lines[0]


def test_broken_inputs_give_one_clear_line(tmp_path: Path) -> None:
    assert "empty file" in _one_line_error(["bag", "info", str(shared("ros1/empty-file.bag"))])
    assert "not a bag" in _one_line_error(["bag", "info", str(shared("ros1/asci-file.txt"))])
    assert "no such file" in _one_line_error(["bag", "info", str(tmp_path / "missing.bag")])
    empty_dir = tmp_path / "empty_dir"
    empty_dir.mkdir()
    assert "no metadata.yaml" in _one_line_error(["bag", "echo", str(empty_dir)])
    odd = tmp_path / "odd"
    odd.mkdir()
    (odd / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: leveldb\n"
        "  relative_file_paths: [odd_0.ldb]\n"
    )
    assert "unknown rosbag2 storage 'leveldb'" in _one_line_error(["bag", "info", str(odd)])
    full = write_ros1_bag(tmp_path / "full.bag")
    truncated = tmp_path / "truncated.bag"
    truncated.write_bytes(full.read_bytes()[: full.stat().st_size // 2])
    assert str(truncated) in _one_line_error(["bag", "info", str(truncated)])
    assert str(truncated) in _one_line_error(["bag", "echo", str(truncated)])
    unindexed = tmp_path / "unindexed.bag"
    data = bytearray(full.read_bytes())
    at = data.index(b"index_pos=") + len(b"index_pos=")
    data[at : at + 8] = bytes(8)
    unindexed.write_bytes(bytes(data))
    assert "rostool bag reindex" in _one_line_error(["bag", "echo", str(unindexed)])
    mcap = tmp_path / "cut.mcap"
    mcap.write_bytes(shared("ros2/talker_mcap/talker.mcap").read_bytes()[:100])
    assert str(mcap) in _one_line_error(["bag", "echo", str(mcap)])
    garbage = tmp_path / "garbage.db3"
    garbage.write_bytes(b"SQLite format 3\x00" + b"\x01" * 200)
    assert str(garbage) in _one_line_error(["bag", "info", str(garbage)])
