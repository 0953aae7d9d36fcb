"""Issue 25: `ros2 bag record --static-topics-path FILE` (rosbag2 PR 2319): the listed topics are subscribed
at once with their given types, before any publisher exists, so a real rclpy talker that starts after the
recording began is recorded from its first message; a bad file is one line and nothing is written. Bags are
read with rosbags and metadata.yaml with PyYAML, not with rostool."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from subprocess import PIPE, STDOUT
from typing import Any

import pytest

from tests.ros2_backends import rostool_lines
from tests.ros2_peers import RclpyPeer, peer_env, rclpy_command
from tests.support import Watched, rostool

Start = Callable[..., RclpyPeer]
STATIC = """static_topics_and_types_list:
  - [/late, std_msgs/msg/String]
  - [late_relative_skipped, std_msgs/String]
"""


def recorder(backend: str, args: list[str], env: dict[str, str], tmp_path: Path, distro: str) -> Watched:
    """`bag record ARGS` on the backend, its stderr (progress lines) read as it comes."""
    if backend == "rclpy":
        command, env = rclpy_command(args, distro), peer_env(env, tmp_path)
    else:
        command = [sys.executable, "-m", "rostool", *args]
    return Watched(subprocess.Popen(command, env=env, stdout=PIPE, stderr=STDOUT, text=True))


def bag_strings(bag: Path) -> tuple[dict[str, str], dict[str, list[str]], dict[str, Any]]:
    """(topic -> type, topic -> the data of its messages in order, topic -> its rosbag2 QoS profiles)."""
    from rosbags.highlevel import AnyReader

    types: dict[str, str] = {}
    found: dict[str, list[str]] = {}
    qos: dict[str, Any] = {}
    with AnyReader([bag]) as reader:
        for conn in reader.connections:
            types[conn.topic] = conn.msgtype
            qos[conn.topic] = conn.ext.offered_qos_profiles
        for conn, _stamp, raw in reader.messages():
            found.setdefault(conn.topic, []).append(str(reader.deserialize(raw, conn.msgtype).data))
    return types, found, qos


def topic_metadata(bag: Path) -> dict[str, dict[str, Any]]:
    import yaml

    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    return {t["topic_metadata"]["name"]: t["topic_metadata"] for t in info["topics_with_message_count"]}


def mcap_schemas(path: Path) -> dict[str, tuple[str, str, bytes]]:
    """topic -> its channel's schema (name, encoding, data), read with the mcap library."""
    from mcap.reader import make_reader

    with path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    return {
        channel.topic: (schema.name, schema.encoding, schema.data)
        for channel in summary.channels.values()
        for schema in [summary.schemas[channel.schema_id]]
    }


def subscribed_before_published(event: dict[str, Any]) -> bool:
    return bool(event["subscribers"].get("/late")) and not event["publishers"].get("/late")


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
@pytest.mark.parametrize("backend", ["dds", "rclpy"])
def test_talker_started_later_is_recorded_from_its_first_message(
    backend: str, distro: str, graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    static = tmp_path / "static.yaml"
    static.write_text(STATIC)
    bag = tmp_path / "static_bag"
    watcher = start_peer("--name", "watcher", "--watch")
    args = ["bag", "record", "--static-topics-path", str(static), "-e", "^/found$", "-x", "skipped"]
    run = recorder(backend, [*args, "-o", str(bag), "--progress", "0.2"], graph_env, tmp_path, distro)
    try:
        # rostool's reader of /late exists, with the file's type, while nothing publishes it; /found is
        # subscribed only once its talker shows its type, and -x leaves the second static topic out
        seen = watcher.wait_for("graph", subscribed_before_published, timeout=30)
        assert seen["topics"]["/late"] == ["std_msgs/msg/String"], seen
        assert "/found" not in seen["topics"] and "/late_relative_skipped" not in seen["topics"], seen
        late = start_peer("--name", "late", "--talk", "/late", "--count", "5", "--subs", "1")
        found = start_peer("--name", "found", "--talk", "/found", "--count", "5", "--subs", "1")
        late.wait_for("sent", timeout=30)
        found.wait_for("sent", timeout=30)
        assert run.wait_for(lambda out: ": 10 msgs on 2 topics" in out, 30), run.stdout
    finally:
        out, _err = run.stop()
    assert run.proc.returncode == 0, out
    assert "recorded 10 messages on 2 topics" in out, out
    types, found_data, _qos = bag_strings(bag)
    assert types == {"/late": "std_msgs/msg/String", "/found": "std_msgs/msg/String"}
    assert found_data["/late"] == [f"hello {i}" for i in range(5)]  # from the very first one
    assert found_data["/found"] == [f"hello {i}" for i in range(5)]
    # the static topic's metadata is what a discovered topic of the same publisher QoS gets
    rows = topic_metadata(bag)
    late_row, found_row = ({k: v for k, v in rows[t].items() if k != "name"} for t in ("/late", "/found"))
    assert late_row == found_row, rows
    schemas = mcap_schemas(next(bag.glob("*.mcap")))  # and the message definition the .mcap holds for it
    assert schemas["/late"] == schemas["/found"] and schemas["/late"][0] == "std_msgs/msg/String", schemas


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
@pytest.mark.parametrize("backend", ["dds", "rclpy"])
def test_best_effort_talker_started_later_is_recorded_with_its_qos(
    backend: str, distro: str, graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """No publisher when subscribing: the reader is reliable (rosbag2's default); a best-effort talker that
    comes later is matched by a best-effort reader instead, and the bag says best_effort."""
    from rosbags.rosbag2.metadata import QosReliability

    static = tmp_path / "static.yaml"
    static.write_text("static_topics_and_types_list:\n  - [/late, std_msgs/msg/String]\n")
    bag = tmp_path / "best_effort.mcap"
    args = ["bag", "record", "--static-topics-path", str(static), "-o", str(bag), "--progress", "0.2"]
    run = recorder(backend, args, graph_env, tmp_path, distro)
    try:
        assert run.wait_for(lambda out: "rostool: recording " in out, 30), run.stdout
        late = start_peer("--name", "late", "--talk", "/late", "--best-effort", "--count", "5", "--subs", "1")
        late.wait_for("sent", timeout=30)
        assert run.wait_for(lambda out: ": 5 msgs on 1 topic" in out, 30), run.stdout
    finally:
        out, _err = run.stop()
    assert run.proc.returncode == 0, out
    types, found, qos = bag_strings(bag)
    assert types == {"/late": "std_msgs/msg/String"} and found["/late"] == [f"hello {i}" for i in range(5)]
    assert [p.reliability for p in qos["/late"]] == [QosReliability.BEST_EFFORT], qos


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_talker_publishing_the_moment_it_matched_is_recorded_whole_on_rclpy(
    distro: str, graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """rosbag2's case for static topics: a node waits for the recorder's subscription (wait_for_matched)
    and publishes at once. On the rclpy backend (the node's own RMW) every message is in the bag. (On the DDS
    backend a Fast DDS writer matches rostool's waiting reader before Cyclone knows the writer: what it
    sends in that moment is lost; CONTRIBUTING.)"""
    static = tmp_path / "static.yaml"
    static.write_text("static_topics_and_types_list:\n  - [/late, std_msgs/msg/String]\n")
    bag = tmp_path / "at_once.mcap"
    args = ["bag", "record", "--static-topics-path", str(static), "-o", str(bag), "--progress", "0.2"]
    run = recorder("rclpy", args, graph_env, tmp_path, distro)
    try:
        assert run.wait_for(lambda out: "rostool: recording " in out, 30), run.stdout
        talker = ["--talk", "/late", "--count", "20", "--rate", "50", "--depth", "100", "--at-once"]
        start_peer("--name", "late", *talker).wait_for("sent", timeout=30)
        assert run.wait_for(lambda out: ": 20 msgs on 1 topic" in out, 30), run.stdout
    finally:
        out, _err = run.stop()
    assert run.proc.returncode == 0, out
    _types, found, _qos = bag_strings(bag)
    assert found["/late"] == [f"hello {i}" for i in range(20)]


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
@pytest.mark.parametrize("backend", ["dds", "rclpy"])
def test_publisher_of_another_type_is_warned_about(
    backend: str, distro: str, graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """A static type that is not the publisher's (a typo in the file): its reader never matches, and the
    user is told once, when that publisher shows up."""
    static = tmp_path / "static.yaml"
    static.write_text("static_topics_and_types_list:\n  - [/late, std_msgs/msg/Int32]\n")
    bag = tmp_path / "typo.mcap"
    args = ["bag", "record", "--static-topics-path", str(static), "-o", str(bag), "--progress", "0.2"]
    run = recorder(backend, args, graph_env, tmp_path, distro)
    warning = "/late is published as std_msgs/msg/String, not std_msgs/msg/Int32"
    try:
        assert run.wait_for(lambda out: "rostool: recording " in out, 30), run.stdout
        talker = start_peer("--name", "late", "--talk", "/late", "--rate", "20")
        talker.wait_for("published", lambda e: e["count"] >= 20, timeout=30)
        assert run.wait_for(lambda out: warning in out, 30), run.stdout
    finally:
        out, _err = run.stop()
    assert run.proc.returncode == 0, out
    assert out.count(warning) == 1, out
    types, found, _qos = bag_strings(bag)
    assert types == {} and found == {}


BAD_FILES = [  # the file's text (None: no file) and how the line goes on after `--static-topics-path FILE: `
    (None, "no such file"),
    ("static_topics_and_types_list: [\n", "not YAML: line 2, column 1: "),
    ("topics: []\n", "Static topics YAML file must have top-level key 'static_topics_and_types_list'"),
    (
        "static_topics_and_types_list: /a\n",
        "Top-level key 'static_topics_and_types_list' must contain a list of 'topic_name, topic_type' pairs",
    ),
    ("static_topics_and_types_list:\n  - [/a]\n", "entry 1 (['/a']) is not a [topic_name, topic_type] pair"),
    ("static_topics_and_types_list:\n  - [/a, '']\n", "Static topic /a has no corresponding type"),
    (
        "static_topics_and_types_list:\n  - [/a, std_msgs/msg/String]\n  - [/a, std_msgs/msg/Int32]\n",
        "/a is listed with two types, std_msgs/msg/String and std_msgs/msg/Int32",
    ),
    ("static_topics_and_types_list: []\n", "'static_topics_and_types_list' lists no topics"),
]


@pytest.mark.parametrize(("content", "expected"), BAD_FILES)
def test_bad_file_is_one_line_and_nothing_is_written(
    content: str | None, expected: str, graph_env: dict[str, str], tmp_path: Path
) -> None:
    static = tmp_path / "static.yaml"
    if content is not None:
        static.write_text(content)
    bag = tmp_path / "never"
    args = ["--ros2", "bag", "record", "--static-topics-path", str(static), "-o", str(bag)]
    done = rostool(args, graph_env)
    assert done.returncode == 1, done.stderr
    lines = done.stderr.splitlines()
    start = f"rostool: --static-topics-path {static}: {expected}"
    assert len(lines) == 1 and lines[0].startswith(start), lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ([] if content is None else ["static.yaml"])


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
@pytest.mark.parametrize("backend", ["dds", "rclpy"])
def test_unknown_type_is_one_line_and_nothing_is_written(
    backend: str, distro: str, graph_env: dict[str, str], tmp_path: Path
) -> None:
    static = tmp_path / "static.yaml"
    static.write_text("static_topics_and_types_list:\n  - [/a, no_such_pkg/msg/Nothing]\n")
    bag = tmp_path / "never"
    args = ["bag", "record", "--static-topics-path", str(static), "-o", str(bag)]
    if backend == "rclpy":
        done = subprocess.run(
            rclpy_command(args, distro), env=peer_env(graph_env, tmp_path), capture_output=True, text=True,
            timeout=60,
        )  # fmt: skip
    else:
        done = rostool(["--ros2", *args], graph_env, timeout=60)
    lines = rostool_lines(done.stderr)
    assert done.returncode == 1 and len(lines) == 1, done.stderr
    assert lines[0].startswith("rostool: ") and "no_such_pkg" in lines[0], lines
    assert not bag.exists()


def test_static_topics_alone_satisfy_ros2_bags_topic_rule(graph_env: dict[str, str], tmp_path: Path) -> None:
    """rosbag2 counts --static-topics-path among the options one needs; without any, its line names it."""
    done = rostool(["--ros2", "bag", "record", "-o", str(tmp_path / "never")], graph_env)
    assert done.returncode == 1
    assert done.stderr.strip() == (
        "rostool: Need to specify at least one option out of --all, --all-topics, --all-services, "
        "--services, --topics, --topic-types,--static-topics-path or --regex"
    )


def test_ros1_form_has_no_static_topics(graph_env: dict[str, str], tmp_path: Path) -> None:
    """ROS 1 learns a topic's type from its publishers only: rosbag record's form has no such flag and refuses
    it as it refuses every ros2 bag record flag (click's usage error), before any master is asked."""
    static = tmp_path / "static.yaml"
    static.write_text(STATIC)
    done = rostool(["--ros1", "bag", "record", "--static-topics-path", str(static), "/late"], graph_env)
    assert done.returncode == 2
    assert "No such option '--static-topics-path'" in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["static.yaml"]
