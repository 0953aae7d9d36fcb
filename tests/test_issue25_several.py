"""Issue 25, several topics at once: `topic bw A B`, `topic hz --all`, `topic bw --all` against real rclpy
and rospy publishers, and `bag info --sort` against rosbags' own counts."""

from __future__ import annotations

import json
import re
from collections.abc import Callable

from tests.ros2_peers import RclpyPeer
from tests.support import Watched, debian_popen, rostool, rostool_popen, stop, wait_until
from tests.test_bag_support import env, shared, true_counts

Start = Callable[..., RclpyPeer]

# CDR sizes on the wire: std_msgs/String "hello N" (N < 1000) is 20 bytes with Fast DDS's padding (see
# test_ros2_real_topics); geometry_msgs/PointStamped with frame_id "map": 4 encapsulation + 8 stamp +
# 4 length + "map\0" + 3 doubles = 44
STRING_BYTES, POINT_BYTES = 20.0, 44.0


def reports(out: str) -> dict[str, dict[str, float]]:
    """The last JSON report of each topic."""
    last: dict[str, dict[str, float]] = {}
    for line in out.splitlines():
        if line.startswith("{"):
            row = json.loads(line)
            last[row["topic"]] = row
    return last


def test_bw_of_two_topics_reports_each_real_size(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    start_peer("--name", "pointer", "--stamped", "/point", "--rate", "20")
    bw = Watched(rostool_popen(["topic", "bw", "/chatter", "/point", "--json"], graph_env))
    try:  # until both topics were reported (discovery may take seconds on a loaded machine)
        assert bw.wait_for(lambda out: set(reports(out)) == {"/chatter", "/point"}, 30), bw.stdout
    finally:
        out, _err = bw.stop()
    got = reports(out)
    assert got["/chatter"]["mean"] == STRING_BYTES and got["/point"]["mean"] == POINT_BYTES, out
    assert got["/point"]["min"] == got["/point"]["max"] == POINT_BYTES

    def table_rows(text: str) -> dict[str, list[str]]:
        return {
            cells[0]: cells
            for cells in map(str.split, text.splitlines())
            if cells[:1] in (["/chatter"], ["/point"])
        }

    table = Watched(rostool_popen(["topic", "bw", "/chatter", "/point"], graph_env))
    try:
        assert table.wait_for(lambda text: len(table_rows(text)) == 2, 30), table.stdout
    finally:
        text, _err = table.stop()
    assert "topic   " in text and "bandwidth" in text, text
    scale = {"B": 1, "KB": 1000, "MB": 1e6}  # ros2 topic bw's one unit per row, chosen by its rate
    for topic, size in (("/chatter", STRING_BYTES), ("/point", POINT_BYTES)):
        cells = table_rows(text)[topic]  # topic, "400", "B/s", then the mean's value and unit
        assert abs(float(cells[3]) * scale[cells[4]] - size) <= scale[cells[4]] / 200, text  # 2 decimals


def both_reported(out: str, key: str) -> bool:
    """Both talkers' topics reported, each over a window of two messages or more."""
    got = reports(out)
    return all(t in got and got[t][key] >= 2 for t in ("/chatter", "/point"))


def test_hz_and_bw_all_measure_every_published_topic(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    start_peer("--name", "pointer", "--stamped", "/point", "--rate", "20")
    listed = lambda: {"/chatter", "/point"} <= set(rostool(["topic", "list"], graph_env).stdout.split())  # noqa: E731
    assert wait_until(listed, 30)  # --all measures the topics published when it starts
    for verb, key in (("hz", "received"), ("bw", "window")):
        run = Watched(rostool_popen(["topic", verb, "--all", "--json"], graph_env))
        try:
            assert run.wait_for(lambda out, key=key: both_reported(out, key), 30), run.stdout
        finally:
            out, _err = run.stop()
        got = reports(out)
        assert not [t for t in got if "/_" in t], got  # hidden topics are left out, as ros2 topic list does
        if verb == "bw":
            assert got["/chatter"]["mean"] == STRING_BYTES and got["/point"]["mean"] == POINT_BYTES, got


def test_ros1_bw_all_table_has_a_line_per_rospy_topic(debian_master: dict[str, str]) -> None:
    env1 = debian_master
    pubs = [
        debian_popen(["rostopic", "pub", "-r", "20", "/beat", "std_msgs/String", "data: x"], env1),
        debian_popen(["rostopic", "pub", "-r", "20", "/count", "std_msgs/Int64", "data: 7"], env1),
    ]
    try:
        listed = lambda: {"/beat", "/count"} <= set(rostool(["--ros1", "topic", "list"], env1).stdout.split())  # noqa: E731
        assert wait_until(listed, 30)  # --all measures the topics published when it starts
        bw = Watched(rostool_popen(["--ros1", "topic", "bw", "--all"], env1))
        try:
            assert bw.wait_for(lambda out: "/beat " in out and "/count " in out, 30), bw.stdout
        finally:
            stop(bw.proc)
        rows = {}
        for line in bw.stdout.splitlines():
            if line.startswith(("/beat ", "/count ")):
                rows[line.split()[0]] = line.split()
        # rostopic bw's units: "x" is 4 length bytes + 1; an int64 is 8 bytes
        assert rows["/beat"][2:5] == ["5.00B", "5.00B", "5.00B"], bw.stdout
        assert rows["/count"][2:5] == ["8.00B", "8.00B", "8.00B"], bw.stdout
        assert "subscribed to [/beat]" in bw.stdout
    finally:
        for pub in pubs:
            stop(pub)


def test_bag_info_sort_orders_topics_ascending() -> None:
    path = shared("ros1/example.bag")
    counts = true_counts(path)
    by_count = json.loads(rostool(["bag", "info", str(path), "--json", "--sort", "count"], env()).stdout)
    assert [t["count"] for t in by_count["topics"]] == sorted(counts.values())
    by_type = json.loads(rostool(["bag", "info", str(path), "--json", "--sort", "type"], env()).stdout)
    types = [t["type"] for t in by_type["topics"]]
    assert types == sorted(types) and len(types) == len(counts)
    mcap = shared("ros2/cdr_test_mcap")  # /array_topic 4 messages, /test_topic 3
    text = rostool(["bag", "info", str(mcap), "--sort", "count"], env()).stdout
    listed = re.findall(r"Topic: (\S+) \| Type: \S+ \| Count: (\d+)", text)
    assert listed == [("/test_topic", "3"), ("/array_topic", "4")], text
    names = rostool(["bag", "info", str(mcap), "-t", "--sort", "name"], env()).stdout.split()
    assert names == ["/array_topic", "/test_topic"]
    bad = rostool(["bag", "info", str(mcap), "--sort", "size"], env())
    assert bad.returncode != 0 and "Traceback" not in bad.stderr


def test_topic_bw_without_a_topic_says_so(graph_env: dict[str, str]) -> None:
    result = rostool(["topic", "bw"], graph_env)
    assert result.returncode != 0 and "no topic to measure" in result.stderr, result.stderr
    assert "Traceback" not in result.stderr
