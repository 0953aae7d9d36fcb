"""`rostool bag convert` / `bag filter`: message-by-message round trips, Debian's rosbag reads our .bag."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from rostool.bag.reader import BagReader
from rostool.output.plain import to_plain
from tests.support import debian, require_ros1_peers, rostool
from tests.test_bag_support import env, shared, true_counts, write_ros1_bag

RENAMED = {"tf/msg/tfMessage": "tf2_msgs/msg/TFMessage"}


def _without_seq(value: Any) -> Any:
    """ROS 2 headers have no `seq`: compare everything else."""
    if isinstance(value, dict):
        return {k: _without_seq(v) for k, v in value.items() if k != "seq"}
    if isinstance(value, list):
        return [_without_seq(v) for v in value]
    return value


def _messages(path: Path) -> list[tuple[str, str, int, Any]]:
    with BagReader([path]) as reader:
        rows = []
        for conn, t, data in reader.messages():
            msg = reader.deserialize(data, conn)
            rows.append(
                (conn.topic, RENAMED.get(conn.msgtype, conn.msgtype), t, _without_seq(to_plain(msg, "ros2")))
            )
    return sorted(rows, key=lambda row: (row[2], row[0]))


def _convert(*args: str) -> None:
    result = rostool(["bag", "convert", *args], env(), timeout=120)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize("source", ["generated", "ros1/example.bag", "ros1/example-bz2.bag"])
def test_bag_mcap_db3_bag_round_trip(tmp_path: Path, source: str) -> None:
    src = write_ros1_bag(tmp_path / "src.bag") if source == "generated" else shared(source)
    original = _messages(src)
    _convert(str(src), str(tmp_path / "a.mcap"))
    _convert(str(tmp_path / "a.mcap"), str(tmp_path / "b.db3"))
    _convert(str(tmp_path / "b.db3"), str(tmp_path / "c.bag"))
    _convert(str(tmp_path / "c.bag"), str(tmp_path / "d"))  # rosbag2 directory
    for step in ("a.mcap", "b.db3", "c.bag", "d"):
        assert _messages(tmp_path / step) == original, step
    assert (tmp_path / "d" / "metadata.yaml").is_file() and (tmp_path / "d" / "d.mcap").is_file()


@pytest.mark.parametrize(
    "name",
    [
        "ros2/talker_mcap",
        "ros2/talker_sqlite3",
        "ros2/cdr_test_mcap",
        "ros2/convert_b_mcap",
        "ros2/split_mcap",
    ],
)
def test_ros2_to_bag_and_back(tmp_path: Path, name: str) -> None:
    src = shared(name)
    original = _messages(src)
    _convert(str(src), str(tmp_path / "x.bag"))
    _convert(str(tmp_path / "x.bag"), str(tmp_path / "back.mcap"))
    _convert(str(tmp_path / "x.bag"), str(tmp_path / "back_dir"), "--format", "db3")
    assert _messages(tmp_path / "x.bag") == original
    assert _messages(tmp_path / "back.mcap") == original
    assert _messages(tmp_path / "back_dir") == original
    assert (tmp_path / "back_dir" / "back_dir.db3").is_file()


def test_outputs_are_readable_by_rosbags_anyreader(tmp_path: Path) -> None:
    from rosbags.highlevel import AnyReader

    src = write_ros1_bag(tmp_path / "src.bag")
    _convert(str(src), str(tmp_path / "out.mcap"))
    _convert(str(src), str(tmp_path / "out.db3"))
    _convert(str(src), str(tmp_path / "out_dir"))
    for out in ("out.mcap", "out.db3", "out_dir"):
        with AnyReader([tmp_path / out]) as reader:  # no default type store: definitions are stored
            decoded = [reader.deserialize(d, c.msgtype) for c, _t, d in reader.messages()]
            assert len(decoded) == 90
            if out != "out.mcap":  # rosbags' mcap writer keeps no type hash in the channel metadata
                assert {c.digest.startswith("RIHS01_") for c in reader.connections} == {True}


def test_debian_rosbag_reads_our_bags(tmp_path: Path) -> None:
    require_ros1_peers()
    for name in ("ros2/talker_mcap", "ros2/cdr_test_sqlite3", "ros1/example-bz2.bag"):
        out = tmp_path / (Path(name).name + ".bag")
        _convert(str(shared(name)), str(out))
        theirs = debian(["rosbag", "info", "--yaml", str(out)], env())
        assert theirs.returncode == 0, theirs.stderr
        info = yaml.safe_load(theirs.stdout)
        expected = true_counts(shared(name))
        assert info["messages"] == sum(expected.values())
        got = {t["topic"]: t["messages"] for t in info["topics"] if t["messages"]}
        assert got == {k: v for k, v in expected.items() if v}
    talker = tmp_path / "talker_mcap.bag"
    echoed = debian(["rostopic", "echo", "-b", str(talker), "/topic", "-n", "2"], env())
    assert echoed.stdout == 'data: "Hello, world! 0"\n---\ndata: "Hello, world! 1"\n---\n'
    types = {
        t["type"]: t["md5"]
        for t in yaml.safe_load(debian(["rosbag", "info", "--yaml", str(talker)], env()).stdout)["types"]
    }
    assert types["std_msgs/String"] == "992ce8a1687cec8c8bd883ec73ca41d1"  # the real ROS 1 md5


def test_selection_options(tmp_path: Path) -> None:
    src = write_ros1_bag(tmp_path / "src.bag")
    _convert(str(src), str(tmp_path / "only.mcap"), "--topics", "/chatter,/tf")
    assert set(true_counts(tmp_path / "only.mcap")) == {"/chatter", "/tf"}
    _convert(str(src), str(tmp_path / "minus.bag"), "--exclude-topics", "/tf")
    assert dict(true_counts(tmp_path / "minus.bag")) == {"/chatter": 30, "/cmd_vel": 30}
    start = 1_700_000_000 + 0.10
    _convert(str(src), str(tmp_path / "window.bag"), "--start", str(start), "--end", "+0.195")
    times = [t for _topic, _type, t, _msg in _messages(tmp_path / "window.bag")]
    assert times == [1_700_000_000_000_000_000 + i * 10_000_000 for i in range(10, 20)]


def test_existing_output_and_failures_leave_no_partial_file(tmp_path: Path) -> None:
    src = write_ros1_bag(tmp_path / "src.bag")
    out = tmp_path / "out.mcap"
    out.write_text("keep me")
    refused = rostool(["bag", "convert", str(src), str(out)], env())
    assert refused.returncode == 1 and "--force" in refused.stderr
    assert out.read_text() == "keep me"
    _convert(str(src), str(out), "--force")
    assert sum(true_counts(out).values()) == 90
    # service events have no ROS 1 type: a clear error naming it, and no DST
    failed = rostool(
        ["bag", "convert", str(shared("ros2/service_events_sqlite3")), str(tmp_path / "se.bag")], env()
    )
    assert failed.returncode == 1
    assert "test_msgs/srv/BasicTypes_Event" in failed.stderr and "Traceback" not in failed.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.mcap", "src.bag"]
    _convert(
        str(shared("ros2/service_events_sqlite3")),
        str(tmp_path / "se.bag"),
        "--exclude-topics",
        "/test_service1/_service_event,/test_service2/_service_event",
    )
    assert sum(true_counts(tmp_path / "se.bag").values()) == 2
    _convert(str(shared("ros2/service_events_sqlite3")), str(tmp_path / "se.mcap"))
    assert len(_messages(tmp_path / "se.mcap")) == 10


def test_ctrl_c_leaves_no_output(tmp_path: Path) -> None:
    import signal

    from tests.support import rostool_popen, wait_until

    src = write_ros1_bag(tmp_path / "big.bag", count=200_000, chunk_threshold=1 << 20)
    proc = rostool_popen(["bag", "convert", str(src), str(tmp_path / "out.db3")], env())
    assert wait_until(lambda: any(p.name.startswith(".out.db3.rostool-") for p in tmp_path.iterdir()), 20)
    proc.send_signal(signal.SIGINT)
    _out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.bag"]


def test_filter_keeps_exactly_the_matching_messages(tmp_path: Path) -> None:
    src = write_ros1_bag(tmp_path / "src.bag")
    out = tmp_path / "fast.bag"
    result = rostool(["bag", "filter", str(src), str(out), "--filter", "m.linear.x > 20"], env())
    assert result.returncode == 0, result.stderr
    kept = _messages(out)
    expected = [row for row in _messages(src) if row[0] == "/cmd_vel" and row[3]["linear"]["x"] > 20]
    assert kept == expected and len(kept) == 16
    assert json.loads(rostool(["bag", "info", "--json", str(out)], env()).stdout)["format"] == "bag"
    by_topic = tmp_path / "tf_late"
    expr = 'topic == "/tf" and t >= 1700000000.5'
    result = rostool(
        ["bag", "filter", str(shared("ros2/talker_mcap")), str(by_topic), "--filter", "topic != '/rosout'"],
        env(),
    )
    assert result.returncode == 0, result.stderr
    assert (by_topic / "metadata.yaml").exists() and dict(true_counts(by_topic)) == {"/topic": 10}
    late = tmp_path / "late.mcap"
    assert rostool(["bag", "filter", str(src), str(late), "--filter", expr], env()).returncode == 0
    times = [t for _topic, _type, t, _msg in _messages(late)]
    assert times and min(times) >= 1_700_000_000_500_000_000
    assert {topic for topic, *_ in _messages(late)} == {"/tf"}
