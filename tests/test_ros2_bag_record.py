"""`bag record` from a ROS 2 graph: what DDS delivers is stored unchanged (.mcap/.db3) or converted (.bag).

Referees: rosbags' reader for the ROS 2 outputs, Debian's rosbag for the ROS 1 output, and the real ROS 2
bytes of ../shared/testdata/ros2/talker_mcap played into the graph and compared byte for byte.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.support import (
    TESTDATA,
    debian,
    interface_workspace,
    require_ros1_peers,
    rostool,
    rostool_popen,
    side_by_side,
    stop,
    wait_until,
)
from tests.test_ros2_graph import ros2_env

TALKER = TESTDATA / "ros2" / "talker_mcap"


@pytest.fixture
def env() -> dict[str, str]:
    return ros2_env()


@pytest.fixture
def publishers(env: dict[str, str]) -> Iterator[None]:
    """A String and a PoseStamped publisher, plus a latched (transient_local) String."""
    procs = [
        rostool_popen(["topic", "pub", "/chatter", "std_msgs/String", "data: hello", "-r", "20"], env),
        rostool_popen(
            ["topic", "pub", "/pose", "geometry_msgs/PoseStamped",
             "{header: {frame_id: map}, pose: {position: {x: 1.5}}}", "-r", "10"],
            env,
        ),
        rostool_popen(["topic", "pub", "--latch", "/mode", "std_msgs/String", "data: auto"], env),
    ]  # fmt: skip
    try:
        assert wait_until(lambda: len(rostool(["topic", "list"], env).stdout.split()) == 3, timeout=20)
        yield
    finally:
        for proc in procs:
            stop(proc)


def read_ros2(path: Path) -> tuple[dict[str, list[object]], dict[str, str], dict[str, int]]:
    """Messages per topic, type per topic and durability per topic as rosbags reads them."""
    from rosbags.highlevel import AnyReader

    messages: dict[str, list[object]] = {}
    with AnyReader([path]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        durability = {
            c.topic: max((q.durability.value for q in c.ext.offered_qos_profiles), default=0)
            for c in reader.connections
        }
        for conn, _stamp, raw in reader.messages():
            messages.setdefault(conn.topic, []).append(reader.deserialize(raw, conn.msgtype))
    return messages, types, durability


def foxglove_decoded(path: Path) -> list[tuple[str, str, Any]]:
    """(topic, schema name, message) of an .mcap as mcap-ros2-support decodes it from the stored schemas."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return [(c.topic, s.name, m) for s, c, _raw, m in reader.iter_decoded_messages()]


@pytest.mark.alone
@pytest.mark.parametrize("suffix", ["mcap", "db3"])
def test_record_all_into_ros2_bags(
    env: dict[str, str], publishers: None, tmp_path: Path, suffix: str
) -> None:
    out = tmp_path / f"run.{suffix}"
    recorded = rostool(["bag", "record", "-a", "-O", str(out), "--duration", "2"], env)
    assert recorded.returncode == 0, recorded.stderr
    assert (
        recorded.stderr.splitlines()[-1].startswith("recorded ")
        and f"on 3 topics to {out}" in recorded.stderr
    )
    messages, types, durability = read_ros2(out)
    assert types == {
        "/chatter": "std_msgs/msg/String",
        "/pose": "geometry_msgs/msg/PoseStamped",
        "/mode": "std_msgs/msg/String",
    }
    assert 25 <= len(messages["/chatter"]) <= 45
    assert {m.data for m in messages["/chatter"]} == {"hello"}  # type: ignore[attr-defined]
    pose = messages["/pose"][0]
    assert (pose.header.frame_id, pose.pose.position.x) == ("map", 1.5)  # type: ignore[attr-defined]
    # the latched message arrives although it was published before recording started
    assert [m.data for m in messages["/mode"]] == ["auto"]  # type: ignore[attr-defined]
    # offered QoS as rosbag2 writes it: TRANSIENT_LOCAL is 1 and VOLATILE 2 in rosbags
    assert durability["/mode"] == 1 and durability["/chatter"] == 2
    if suffix == "mcap":  # a second, independent reader: Foxglove's decoder, from the schemas in the file
        decoded = foxglove_decoded(out)
        assert len(decoded) == sum(len(v) for v in messages.values())
        poses = [msg for topic, _schema, msg in decoded if topic == "/pose"]
        assert poses[0].header.frame_id == "map" and poses[0].pose.position.x == 1.5
        assert {schema for _topic, schema, _msg in decoded} == set(types.values())


def test_default_name_is_a_dated_rosbag2_directory(
    env: dict[str, str], publishers: None, tmp_path: Path
) -> None:
    """ros2 bag record's default: rosbag2_YYYY_MM_DD-HH_MM_SS/ with metadata.yaml and NAME_0.mcap."""
    recorded = rostool(["bag", "record", "/chatter", "--duration", "1"], env, cwd=tmp_path)
    assert recorded.returncode == 0, recorded.stderr
    (produced,) = tmp_path.iterdir()
    assert produced.name.startswith("rosbag2_") and produced.name.count("_") == 5
    assert sorted(p.name for p in produced.iterdir()) == ["metadata.yaml", f"{produced.name}_0.mcap"]
    messages, _types, _qos = read_ros2(produced)
    assert list(messages) == ["/chatter"]


def test_record_into_ros1_bag_read_by_debian_rosbag(
    env: dict[str, str], publishers: None, tmp_path: Path
) -> None:
    require_ros1_peers()
    out = tmp_path / "run.bag"
    recorded = rostool(["bag", "record", "/pose", "/mode", "-O", str(out), "--duration", "1.5"], env)
    assert recorded.returncode == 0, recorded.stderr
    info = yaml.safe_load(debian(["rosbag", "info", "--yaml", str(out)], env).stdout)
    assert {t["topic"]: t["type"] for t in info["topics"]} == {
        "/pose": "geometry_msgs/PoseStamped",
        "/mode": "std_msgs/String",
    }
    assert {t["type"]: t["md5"] for t in info["types"]} == {
        "geometry_msgs/PoseStamped": "d3812c3cbc69362b77dc0b19b345f8f5",
        "std_msgs/String": "992ce8a1687cec8c8bd883ec73ca41d1",
    }
    echoed = debian(["rostopic", "echo", "-b", str(out), "-n", "1", "/pose/pose/position/x"], env)
    assert echoed.stdout.split("\n")[0] == "1.5", echoed.stderr


def test_real_ros2_bytes_are_recorded_unchanged(env: dict[str, str], tmp_path: Path) -> None:
    """rosbag2's /rosout and /topic samples go through DDS twice (play, record) and come out identical."""
    from rostool.bag.reader import BagReader

    out = tmp_path / "replayed.mcap"
    recorder = rostool_popen(["bag", "record", "/rosout", "/topic", "-O", str(out)], env)
    try:
        # nothing is played before the recorder's readers exist: play waits for a subscriber on every topic
        selected = ["--topics", "/rosout", "/topic"]  # rosbag's form: the bag first
        played = rostool(["bag", "play", "-r", "4", "--wait-for-subscribers", str(TALKER), *selected], env)
        assert played.returncode == 0, played.stderr
        time.sleep(1.0)
    finally:
        _out, err = stop(recorder)
    assert recorder.returncode == 0, err

    def raw_by_topic(path: Path) -> dict[str, list[bytes]]:
        found: dict[str, list[bytes]] = {}
        with BagReader([path]) as reader:  # rosbags' AnyReader yields no messages of this v4 bag
            for conn, _stamp, raw in reader.messages():
                found.setdefault(conn.topic, []).append(bytes(raw))
        return found

    original = raw_by_topic(TALKER)
    original.pop("/parameter_events", None)
    assert raw_by_topic(out) == original


def test_incompatible_qos_is_reported(env: dict[str, str], tmp_path: Path) -> None:
    publisher = rostool_popen(
        ["topic", "pub", "/scan_like", "std_msgs/String", "data: x", "-r", "10", "--qos-reliability",
         "best_effort"],
        env,
    )  # fmt: skip
    try:
        recorded = rostool(
            ["bag", "record", "/scan_like", "--qos-reliability", "reliable", "-O", str(tmp_path / "q.mcap"),
             "--duration", "2.5"],
            env,
        )  # fmt: skip
    finally:
        stop(publisher)
    assert recorded.returncode == 0, recorded.stderr
    assert "incompatible policy RELIABILITY" in recorded.stderr, recorded.stderr
    assert "recorded 0 messages" in recorded.stderr


def test_qos_options_are_refused_on_ros1(tmp_path: Path) -> None:
    env = ros2_env()
    env["ROS_VERSION"] = "1"
    env["ROS_MASTER_URI"] = "http://127.0.0.1:9"
    refused = rostool(["bag", "record", "/x", "--qos-depth", "5", "-O", str(tmp_path / "x.bag")], env)
    assert refused.returncode != 0
    assert refused.stderr.count("\n") == 1, refused.stderr
    assert not list(tmp_path.iterdir())


def test_custom_types_from_sources_are_recorded_self_describing(tmp_path: Path) -> None:
    from tests.test_ros2_interfaces import SOURCES

    env = ros2_env()
    sources = interface_workspace(tmp_path / "ws", SOURCES)
    status = "{name: r2, parts: [{label: arm, weight: 1.5}], where: {x: 1.0}}"
    publisher = rostool_popen(["topic", "pub", "/status", "robo_msgs/msg/Status", status, "-r", "10",
                               "--interfaces", str(sources)], env)  # fmt: skip
    out = tmp_path / "custom.mcap"
    try:
        blind_out = tmp_path / "blind.mcap"
        blind, recorded = side_by_side([
            lambda: rostool(["bag", "record", "/status", "-O", str(blind_out), "--duration", "2"], env),
            lambda: rostool(["bag", "record", "/status", "-O", str(out), "--duration", "2", "--interfaces",
                             str(sources)], env),
        ])  # fmt: skip
    finally:
        stop(publisher)
    # without the sources the type comes from the publisher's type description service
    assert blind.returncode == 0 and "recorded 0 messages" not in blind.stderr, blind.stderr
    assert foxglove_decoded(blind_out)[0][2].parts[0].label == "arm"
    assert recorded.returncode == 0, recorded.stderr
    # the bag carries the definitions: no --interfaces needed, by rostool or by Foxglove's decoder
    first = foxglove_decoded(out)[0][2]
    assert (first.name, first.parts[0].label, first.where.x) == ("r2", "arm", 1.0)
    echoed = rostool(["bag", "echo", str(out), "/status", "-n", "1", "--json"], ros2_env())
    assert json.loads(echoed.stdout) == {
        "name": "r2",
        "parts": [{"label": "arm", "weight": 1.5}],
        "where": {"x": 1.0, "y": 0.0, "z": 0.0},
    }, echoed.stderr


def test_hidden_topics_only_when_asked(env: dict[str, str], tmp_path: Path) -> None:
    procs = [
        rostool_popen(["topic", "pub", topic, "std_msgs/String", "data: x", "-r", "10"], env)
        for topic in ("/visible", "/robot/_internal")
    ]
    try:
        listed = ["topic", "list", "--include-hidden-topics"]  # ros2 topic list hides /_name topics
        assert wait_until(lambda: len(rostool(listed, env).stdout.split()) == 2, timeout=20)
        recording = ["bag", "record", "-a", "--duration", "1.5", "-O"]
        plain, hidden = side_by_side([
            lambda: rostool([*recording, str(tmp_path / "plain.mcap")], env),
            lambda: rostool([*recording, str(tmp_path / "all.mcap"), "--include-hidden-topics"], env),
        ])  # fmt: skip
    finally:
        for proc in procs:
            stop(proc)
    assert plain.returncode == 0 and hidden.returncode == 0, plain.stderr + hidden.stderr
    assert set(read_ros2(tmp_path / "plain.mcap")[1]) == {"/visible"}
    assert set(read_ros2(tmp_path / "all.mcap")[1]) == {"/visible", "/robot/_internal"}
