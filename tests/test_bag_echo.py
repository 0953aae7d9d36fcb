"""`rostool bag echo`: every message of every shared bag decodes; output as rostopic/ros2 print it."""

from __future__ import annotations

import json

import pytest

from rostool.bag.reader import BagReader
from tests.support import debian, require_ros1_peers, rostool
from tests.test_bag_support import ALL_BAGS, env, shared, true_counts


@pytest.mark.parametrize("name", ALL_BAGS)
def test_reader_decodes_every_message(name: str) -> None:
    path = shared(name)
    decoded = 0
    with BagReader([path]) as reader:
        for conn, _t, data in reader.messages():
            msg = reader.deserialize(data, conn)
            assert getattr(msg, "__msgtype__", "") == conn.msgtype
            decoded += 1
    assert decoded == sum(true_counts(path).values())


@pytest.mark.parametrize(("name", "count"), [("ros1/example.bag", 8647), ("ros2/split_mcap", 6074)])
def test_echo_prints_every_message(name: str, count: int) -> None:
    result = rostool(["bag", "echo", str(shared(name))], env(), timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("\n---\n") + result.stdout.startswith("---\n") == count
    headers = [line for line in result.stdout.splitlines() if line.startswith("# /") or line.startswith("# ")]
    assert len(headers) == count  # several topics: one `# TOPIC @ T` line per message


def test_echo_json_split_bag_topics() -> None:
    result = rostool(["bag", "echo", str(shared("ros2/split_mcap")), "--json"], env(), timeout=120)
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert len(lines) == 6074
    assert {line["topic"] for line in lines} == {"AAA", "BBB", "CCC", "DDD", "EEE", "FFF", "GGG", "HHH"}
    assert all(isinstance(line["msg"]["data"], str) for line in lines)
    times = [line["t"] for line in lines]
    assert times == sorted(times)


@pytest.mark.parametrize("name", ["ros2/cdr_test_mcap", "ros2/cdr_test_sqlite3"])
def test_echo_cdr_primitive_and_array_values(name: str) -> None:
    basic = rostool(["bag", "echo", str(shared(name)), "/test_topic", "--json"], env())
    rows = [json.loads(line) for line in basic.stdout.splitlines()]
    assert len(rows) == 3
    assert rows[0] == {
        "bool_value": False, "byte_value": 0, "char_value": 0, "float32_value": 0.0, "float64_value": 0.0,
        "int8_value": 0, "uint8_value": 0, "int16_value": 0, "uint16_value": 0, "int32_value": 123,
        "uint32_value": 0, "int64_value": 0, "uint64_value": 0,
    }  # fmt: skip
    arrays = rostool(["bag", "echo", str(shared(name)), "/array_topic", "--json"], env())
    rows = [json.loads(line) for line in arrays.stdout.splitlines()]
    assert len(rows) == 4
    first = rows[0]
    assert first["bool_values"] == [True, False, True]
    assert first["string_values"] == ["Complex Hello1", "Complex Hello2", "Complex Hello3"]
    assert first["int32_values"] == [0, 0, 0] and first["float64_values"] == [0.0, 0.0, 0.0]
    assert len(first["basic_types_values"]) == 3 and first["basic_types_values"][0]["int32_value"] == 0
    yaml_text = rostool(["bag", "echo", str(shared(name)), "/test_topic", "-n", "1"], env()).stdout
    assert yaml_text.splitlines()[:2] == ["bool_value: false", "byte_value: 0"]
    assert "int32_value: 123" in yaml_text.splitlines() and yaml_text.endswith("\n---\n")


def test_echo_service_events() -> None:
    path = shared("ros2/service_events_sqlite3")
    result = rostool(["bag", "echo", str(path), "/test_service1/_service_event", "--json"], env())
    events = [json.loads(line) for line in result.stdout.splitlines()]
    assert len(events) == 4
    # client side: REQUEST_SENT (0) then RESPONSE_RECEIVED (3), for two calls
    assert [e["info"]["event_type"] for e in events] == [0, 3, 0, 3]
    assert [e["info"]["sequence_number"] for e in events] == [1, 1, 2, 2]
    assert [len(e["request"]) for e in events] == [1, 0, 1, 0]
    assert [len(e["response"]) for e in events] == [0, 1, 0, 1]
    assert "REQUEST_SENT" not in events[0]["info"]  # constants are not fields
    assert len(events[0]["info"]["client_gid"]) == 16


def test_echo_talker_without_definitions_uses_distro_store() -> None:
    for name in ("ros2/talker_mcap", "ros2/talker_sqlite3"):
        result = rostool(["bag", "echo", str(shared(name)), "/rosout", "--json", "-n", "1"], env())
        log = json.loads(result.stdout)
        assert log["name"] == "minimal_publisher" and log["msg"] == "Publishing: 'Hello, world! 0'"
        assert log["stamp"] == {"sec": 1585866235, "nanosec": 112130688}
    for distro in ("humble", "iron", "foxy"):
        result = rostool(
            ["bag", "echo", str(shared("ros2/talker_mcap")), "/topic", "--distro", distro], env()
        )
        assert result.stdout.splitlines()[0] == "data: Hello, world! 0"


@pytest.mark.parametrize("topic", ["/turtle1/pose", "/tf", "/rosout", "/turtle2/cmd_vel"])
def test_echo_ros1_matches_rostopic_echo_b(topic: str) -> None:
    require_ros1_peers()
    path = str(shared("ros1/example.bag"))
    theirs = debian(["rostopic", "echo", "-b", path, topic, "-n", "5"], env())
    ours = rostool(["bag", "echo", path, topic, "-n", "5"], env())
    assert ours.returncode == 0, ours.stderr
    assert ours.stdout == theirs.stdout


def test_echo_options() -> None:
    path = str(shared("ros1/example.bag"))
    csv_out = rostool(["bag", "echo", path, "/turtle1/pose", "--csv", "-n", "2"], env()).stdout.splitlines()
    assert csv_out[0] == "%time,field.x,field.y,field.theta,field.linear_velocity,field.angular_velocity"
    assert csv_out[1].startswith("1396293888056045055,5.544444561004639,")
    fields = rostool(["bag", "echo", path, "/turtle1/pose", "--field", "x", "-n", "1"], env()).stdout
    assert fields == "5.544444561004639\n---\n"
    noarr = rostool(["bag", "echo", path, "/tf", "--noarr", "-n", "1"], env()).stdout
    assert noarr.startswith('transforms: "<array type: geometry_msgs/TransformStamped, length: 1>"')
    expr = 'topic == "/turtle1/cmd_vel" and m.linear.x > 1.5 and t < 1396293900'
    filtered = [
        json.loads(line)
        for line in rostool(["bag", "echo", path, "--json", "--filter", expr], env()).stdout.splitlines()
    ]
    expected = 0
    with BagReader([path]) as reader:
        for conn, t, data in reader.messages(reader.select(["/turtle1/cmd_vel"])):
            expected += reader.deserialize(data, conn).linear.x > 1.5 and t < 1396293900 * 10**9
    assert expected > 0 and len(filtered) == expected
    assert all(f["topic"] == "/turtle1/cmd_vel" and f["msg"]["linear"]["x"] > 1.5 for f in filtered)
    bad = rostool(["bag", "echo", path, "/nope"], env())
    assert bad.returncode == 1 and "topic /nope is not in the bag" in bad.stderr
    unsafe = rostool(["bag", "echo", path, "--filter", "__import__('os')"], env())
    assert unsafe.returncode == 1 and "Traceback" not in unsafe.stderr


@pytest.mark.parametrize("name", ["ros1/example.bag", "ros1/example-bz2.bag"])
def test_ros1_reader_yields_what_rosbags_yields(name: str) -> None:
    from rosbags.rosbag1 import Reader

    with Reader(shared(name)) as theirs:
        expected = sorted((c.topic, t, bytes(d)) for c, t, d in theirs.messages())
    with BagReader([shared(name)]) as ours:
        got = [(c.topic, t, bytes(d)) for c, t, d in ours.messages()]
    assert [t for _c, t, _d in got] == sorted(t for _c, t, _d in got)
    assert sorted(got) == expected


def test_several_bags_at_once(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from tests.test_bag_support import write_ros1_bag

    extra = write_ros1_bag(tmp_path / "extra.bag")
    with BagReader([shared("ros1/example.bag"), extra]) as reader:
        times = [t for _c, t, _d in reader.messages()]
        assert len(times) == 8647 + 90 and times == sorted(times)
        assert reader.topics["/tf"].count == 2688 + 30
    files = sorted((shared("ros2/split_mcap")).glob("*.mcap"))
    result = rostool(["bag", "info", "--json", *map(str, files)], env())
    assert sum(d["messages"] for d in json.loads(result.stdout)) == 6074
    merged = tmp_path / "merged.mcap"
    args = ["bag", "convert", *map(str, files), str(merged)]
    assert rostool(args, env()).returncode == 0
    assert sum(true_counts(merged).values()) == 6074
    mixed = rostool(["bag", "echo", str(shared("ros1/example.bag")), "/x"], env())
    assert mixed.returncode == 1
