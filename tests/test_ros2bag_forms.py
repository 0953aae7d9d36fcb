"""`rostool bag record/play/info` under ROS 2 speak `ros2 bag`'s argument forms and print its layout.

Referee: rosbag2's ros2bag CLI tests (ros2/rosbag2 ros2bag/test: test_record.py, test_info.py,
test_recorder_args_parser.py, test_player_args_parser.py) and rosbag2_py's format_bag_metadata.cpp; their
command lines and expected lines are ported here as facts. The live cases run against real rclpy peers
(tests/ros2_peers.py), the bags written are read back with rosbags, and the real bags of
/work/shared/testdata are the info inputs.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.ros2_peers import StartPeer
from tests.support import TESTDATA, Watched, rostool, rostool_popen, stop, wait_until
from tests.test_ros2_graph import ros2_env

ROS2 = TESTDATA / "ros2"
INDENT = " " * 19
Peer = Callable[..., Any]


def utc() -> dict[str, str]:
    return ros2_env(TZ="UTC")


def read_rosbags(path: Path) -> dict[str, list[object]]:
    from rosbags.highlevel import AnyReader

    found: dict[str, list[object]] = {}
    with AnyReader([path]) as reader:
        for conn, _stamp, raw in reader.messages():
            found.setdefault(conn.topic, []).append(reader.deserialize(raw, conn.msgtype))
    return found


# -- info: format_bag_metadata's layout --------------------------------------------------------------
def test_info_of_a_rosbag2_bag_is_ros2_bag_info_layout() -> None:
    out = rostool(["bag", "info", str(ROS2 / "talker_mcap")], utc()).stdout.splitlines()
    assert out == [
        "",
        "Files:             talker.mcap",
        "Bag size:          14.2 KiB",
        "Storage id:        mcap",
        "ROS Distro:        unknown",
        "Duration:          4.531096768s",
        "Start:             Apr  2 2020 22:23:55.112411371 (1585866235.112411371)",
        "End:               Apr  2 2020 22:23:59.643508139 (1585866239.643508139)",
        "Messages:          20",
        "Topic information: Topic: /parameter_events | Type: rcl_interfaces/msg/ParameterEvent | Count: 0 | "
        "Serialization Format: cdr",
        INDENT + "Topic: /rosout | Type: rcl_interfaces/msg/Log | Count: 10 | Serialization Format: cdr",
        INDENT + "Topic: /topic | Type: std_msgs/msg/String | Count: 10 | Serialization Format: cdr",
        "Service:           0",
        "Service information: ",
    ]


def test_info_lists_service_events_as_services() -> None:
    out = rostool(["bag", "info", str(ROS2 / "service_events_sqlite3")], utc()).stdout.splitlines()
    assert "Messages:          2" in out  # service events are not counted as messages
    assert "Service:           2" in out
    assert (
        "Service information: Service: /test_service1 | Type: test_msgs/srv/BasicTypes | Event Count: 4 | "
        "Serialization Format: cdr"
    ) in out
    assert not any("_service_event" in line for line in out if "Topic: " in line)


def test_info_split_bag_lists_every_file() -> None:
    out = rostool(["bag", "info", str(ROS2 / "split_mcap")], utc()).stdout.splitlines()
    assert out[1:6] == ["Files:             wbag_0.mcap", *(f"{' ' * 19}wbag_{i}.mcap" for i in range(1, 5))]
    assert "Messages:          6074" in out


def test_info_topic_names_and_verbose_services() -> None:
    """ros2bag test_info.py: `info --topic-name empty_bag` prints "/parameter_events\\n/rosout\\n"; -v
    counts requests and responses per service."""
    from rostool.bag.info import bag_info, format_text

    empty = format_text(bag_info(ROS2 / "empty_bag_sqlite3"), topic_name=True)
    assert empty + "\n" == "/parameter_events\n/rosout\n"
    text = format_text(bag_info(ROS2 / "service_events_sqlite3"), verbose=True)
    assert (
        "Service information: Service: /test_service1 | Type: test_msgs/srv/BasicTypes | Request Count: 2 | "
        "Response Count: 2 | Serialization Format: cdr"
    ) in text.splitlines()


def test_info_of_a_ros1_bag_stays_rosbag_layout() -> None:
    out = rostool(["bag", "info", str(TESTDATA / "ros1" / "example.bag")], utc()).stdout
    assert out.startswith("path:") and "Topic information" not in out


# -- record: ros2bag's validate_parsed_arguments, through our parser ----------------------------------
RECORD_ERRORS = [
    (["--output", "x"], "Need to specify at least one option out of --all, --all-topics"),
    (
        ["--exclude-regex", "%s-%s", "--services", "service1", "--topics", "topic1", "--output", "x"],
        "--exclude-regex argument requires either --all, --all-topics, --topic-types, --all-services or "
        "--regex",
    ),
    (
        ["--exclude-topics", "topic1", "--all-services", "--topics", "topic1", "--output", "x"],
        "--exclude-topics argument requires either --all, --all-topics, --topic-types or --regex",
    ),
    (
        ["--exclude-topic-types", "/topic_type1", "--all-services", "--topics", "topic1", "--output", "x"],
        "--exclude-topic-types argument requires either --all, --all-topics or --regex",
    ),
    (
        ["--exclude-services", "service1", "--services", "service1", "--all-topics", "--output", "x"],
        "--exclude-services argument requires either --all, --all-services or --regex",
    ),
    (
        ["-a", "--compression-format", "zstd", "--output", "x"],
        "Cannot specify compression format without a compression mode",
    ),
    (["-a", "--use-sim-time", "--no-discovery"], "--use-sim-time and --no-discovery both set"),
    (
        ["-a", "--snapshot-mode", "--max-cache-size", "0"],
        "In snapshot mode, either the max_cache_duration or max_cache_size shall not be set to zero",
    ),
]


@pytest.mark.parametrize(("args", "expected"), RECORD_ERRORS)
def test_record_argument_errors_are_ros2bag_s(args: list[str], expected: str, tmp_path: Path) -> None:
    result = rostool(["--ros2", "bag", "record", *args], ros2_env(), cwd=tmp_path)
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], result.stderr


def test_record_refuses_an_existing_output_folder(tmp_path: Path) -> None:
    (tmp_path / "taken").mkdir()
    result = rostool(["--ros2", "bag", "record", "-a", "-o", str(tmp_path / "taken")], ros2_env())
    assert result.returncode != 0 and "Output folder" in result.stderr and "already exists" in result.stderr


# -- record and play against real rclpy peers ----------------------------------------------------
def _record(args: list[str], env: dict[str, str], cwd: Path, talkers: list[Any], messages: int) -> str:
    """Record until every talker (an RclpyPeer with --talk or --stamped) has seen the recorder subscribe
    and has published `messages` more since; then Ctrl+C. Returns the recorder's stderr."""
    started = time.monotonic()
    proc = rostool_popen(["--ros2", "bag", "record", *args], env, cwd=cwd)
    try:
        for talker in talkers:
            matched = talker.wait_for("matched", lambda e: e["subscribers"] > 0 and e["t"] > started, 60)
            more = lambda e, m=matched: e["count"] >= m["count"] + messages  # noqa: E731
            talker.wait_for(matched["progress"], more, 60)
    finally:
        _out, err = stop(proc)
    assert proc.returncode == 0, err
    return err


def test_record_writes_a_rosbag2_directory_named_by_o(
    start_peer: Peer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """ros2bag test_record.py: `record -a -s STORAGE --output DIR` exits 0 on SIGINT; the directory is
    exactly DIR and rosbags reads it. (Its "Listening for topics..."/"Recording..." lines are printed on a
    terminal only: piped, stderr holds one summary line, as the other recorders' tests require.)"""
    talker = start_peer("--talk", "/chatter", "--rate", "20")
    stderr = _record(["-a", "-s", "sqlite3", "--output", "out"], graph_env, tmp_path, [talker], 50)
    assert stderr.startswith("recorded ") and stderr.count("\n") == 1, stderr
    bag = tmp_path / "out"
    assert sorted(p.name for p in bag.iterdir()) == ["metadata.yaml", "out_0.db3"]
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "sqlite3" and meta["relative_file_paths"] == ["out_0.db3"]
    messages = read_rosbags(bag)
    assert len(messages["/chatter"]) >= 10
    assert all(m.data.startswith("hello") for m in messages["/chatter"])  # type: ignore[attr-defined]
    info = rostool(["bag", "info", str(bag)], graph_env).stdout.splitlines()
    assert "Storage id:        sqlite3" in info
    count = len(messages["/chatter"])
    assert any(
        line.endswith(
            f"Topic: /chatter | Type: std_msgs/msg/String | Count: {count} | Serialization Format: cdr"
        )
        for line in info
    )


def test_record_splits_by_duration_and_compresses(
    start_peer: Peer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """-d splits into NAME_0.mcap, NAME_1.mcap, ...; --compression-mode message with zstd; --topics a b."""
    talker = start_peer("--talk", "/chatter", "--rate", "20")
    args = ["--topics", "/chatter", "/absent", "-o", "split", "-d", "1"]
    compressed = ["--compression-mode", "message", "--compression-format", "zstd"]
    _record([*args, *compressed], graph_env, tmp_path, [talker], 70)
    bag = tmp_path / "split"
    files = sorted(p.name for p in bag.glob("*.mcap"))
    assert len(files) >= 2 and files[0] == "split_0.mcap"
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert sorted(meta["relative_file_paths"]) == files
    assert meta["compression_mode"] == "MESSAGE" and meta["compression_format"] == "zstd"
    messages = read_rosbags(bag)
    assert set(messages) == {"/chatter"} and meta["message_count"] == len(messages["/chatter"]) >= 20
    echoed = rostool(["bag", "echo", str(bag), "/chatter", "-n", "1", "--json"], graph_env)
    assert '"data": "hello' in echoed.stdout


def test_play_forms_topics_clock_and_remap(
    start_peer: Peer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """`play BAG --topics a b --clock 100 --remap old:=new -r 2`: 100 is the clock rate, b a topic."""
    listener = start_peer("--listen", "/talk")
    play = [
        "--ros2", "bag", "play", str(ROS2 / "talker_mcap"), "--topics", "/topic", "/rosout",
        "--clock", "100", "--remap", "/topic:=/talk", "-r", "2", "-d", "1",
    ]  # fmt: skip
    result = rostool(play, graph_env, timeout=60)
    assert result.returncode == 0, result.stderr
    assert wait_until(lambda: len(listener.of("heard")) >= 10, timeout=10)
    assert [e["data"] for e in listener.of("heard")] == [f"Hello, world! {i}" for i in range(10)]


def test_play_start_offset_and_playback_duration(start_peer: Peer, graph_env: dict[str, str]) -> None:
    """--start-offset and --playback-duration cut the bag as ros2 bag play does (bag time)."""
    listener = start_peer("--listen", "/topic")
    play = [
        "--ros2", "bag", "play", "-d", "1", "--start-offset", "2", "--playback-duration", "1.5",
        str(ROS2 / "talker_mcap"), "--topics", "/topic",
    ]  # fmt: skip
    result = rostool(play, graph_env, timeout=60)
    assert result.returncode == 0, result.stderr
    from rostool.bag.reader import BagReader

    with BagReader([ROS2 / "talker_mcap"]) as reader:
        start = reader.start_ns
        expected = [
            reader.deserialize(raw, conn).data  # type: ignore[attr-defined]
            for conn, stamp, raw in reader.messages(reader.select(["/topic"]))
            if start + 2e9 <= stamp <= start + 3.5e9
        ]
    wait_until(lambda: len(listener.of("heard")) >= len(expected), timeout=10)
    assert [e["data"] for e in listener.of("heard")] == expected


def test_play_refuses_a_storage_that_is_not_the_bag_s() -> None:
    result = rostool(["--ros2", "bag", "play", "-s", "sqlite3", str(ROS2 / "talker_mcap")], ros2_env())
    assert result.returncode != 0 and "-s sqlite3 given, but the bag's storage is mcap" in result.stderr


def test_record_split_by_size_keeps_max_bag_files_compressed(
    start_peer: Peer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """-b BYTES --max-bag-files N --compression-mode file: N zstd files remain, listed in metadata.yaml."""
    talker = start_peer("--talk", "/chatter", "--rate", "50")
    args = ["--topics", "/chatter", "-s", "sqlite3", "-o", "ring", "-b", "600", "--max-bag-files", "2"]
    compressed = ["--compression-mode", "file", "--compression-format", "zstd"]
    _record([*args, *compressed], graph_env, tmp_path, [talker], 130)
    bag = tmp_path / "ring"
    files = sorted(p.name for p in bag.iterdir() if p.name != "metadata.yaml")
    assert len(files) == 2 and all(f.startswith("ring_") and f.endswith(".db3.zstd") for f in files), files
    assert files[0] != "ring_0.db3.zstd"  # the oldest were deleted
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert sorted(meta["relative_file_paths"]) == files and meta["compression_mode"] == "FILE"
    assert len(read_rosbags(bag)["/chatter"]) == meta["message_count"] > 0


def test_record_use_sim_time_stamps_with_clock(
    start_peer: Peer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """--use-sim-time: the stored receive times are /clock's (here 1000 s), not the wall clock."""
    talker = start_peer("--talk", "/chatter", "--rate", "20")
    clock = rostool_popen(
        ["topic", "pub", "/clock", "rosgraph_msgs/msg/Clock", "{clock: {sec: 1000}}", "-r", "20"], graph_env
    )
    try:
        listed = lambda: "/clock" in rostool(["topic", "list"], graph_env).stdout.split()  # noqa: E731
        assert wait_until(listed, timeout=20)
        _record(["--topics", "/chatter", "--use-sim-time", "-o", "sim"], graph_env, tmp_path, [talker], 60)
    finally:
        stop(clock)
    from rosbags.highlevel import AnyReader

    with AnyReader([tmp_path / "sim"]) as reader:
        stamps = [stamp for _conn, stamp, _raw in reader.messages()]
    assert stamps and all(stamp == 1000 * 10**9 for stamp in stamps)


def test_bag_without_definitions_decodes_with_a_sourced_ros2(tmp_path: Path) -> None:
    """A rosbag2 bag that stores no definition of test_msgs/msg/BasicTypes decodes where the package is
    installed (AMENT_PREFIX_PATH of the Jazzy peer venv, which has ros-jazzy-test-msgs), as ros2 bag does."""
    import shutil
    import sqlite3

    from tests.ros2_peers import PEERS_DIR, peer_python

    peer_python("jazzy")  # fails in CI, skips elsewhere, without the venv
    bag = tmp_path / "nodef"
    shutil.copytree(ROS2 / "cdr_test_sqlite3", bag)
    with sqlite3.connect(bag / "cdr_test_0.db3") as db:
        db.execute("DELETE FROM message_definitions")
    env = ros2_env()
    env.pop("AMENT_PREFIX_PATH", None)
    blind = rostool(["bag", "echo", str(bag), "/test_topic", "-n", "1"], env, cwd=tmp_path)
    assert blind.returncode != 0 and "cannot decode test_msgs/msg/BasicTypes" in blind.stderr
    assert (PEERS_DIR / "jazzy" / "share" / "test_msgs" / "msg" / "BasicTypes.msg").exists()
    env["AMENT_PREFIX_PATH"] = str(PEERS_DIR / "jazzy")
    sourced = rostool(["bag", "echo", str(bag), "/test_topic", "-n", "1", "--json"], env, cwd=tmp_path)
    assert sourced.returncode == 0, sourced.stderr
    assert '"int32_value": 123' in sourced.stdout


def test_record_filters_types_exclusions_regex_and_custom_data(
    start_peer: StartPeer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """ros2bag test_recorder_args_parser's lists, recorded for real: --topic-types T, --custom-data K=V K=V,
    -a --exclude-topics T, -e RE (a name containing RE)."""
    talker, stamped = start_peer.together(
        ["--talk", "/chatter", "--rate", "20"], ["--stamped", "/point", "--rate", "20"]
    )
    typed = [
        "--topic-types",
        "std_msgs/msg/String",
        "--custom-data",
        "Key1=Value1",
        "key2=value2",
        "-o",
        "typed",
    ]
    _record(typed, graph_env, tmp_path, [talker], 30)
    _record(["-a", "--exclude-topics", "/chatter", "-o", "excluded"], graph_env, tmp_path, [stamped], 30)
    _record(["-e", "oin", "-o", "regex"], graph_env, tmp_path, [stamped], 30)
    assert set(read_rosbags(tmp_path / "typed")) == {"/chatter"}
    meta = yaml.safe_load((tmp_path / "typed" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["custom_data"] == {"Key1": "Value1", "key2": "value2"}
    excluded = set(read_rosbags(tmp_path / "excluded"))
    assert "/point" in excluded and "/chatter" not in excluded
    assert set(read_rosbags(tmp_path / "regex")) == {"/point"}


def test_play_lists_in_one_value_exclusions_and_clock_topics(
    start_peer: Peer, graph_env: dict[str, str]
) -> None:
    """ros2bag test_player_args_parser: `--topics 'topic1 topic2'`, `--exclude-topics`, `--remap 'a:=b c:=d'`
    and `--clock-topics T` (each /topic message's time on /clock), played into a real listener."""
    from rostool.bag.reader import BagReader

    listener = start_peer("--listen", "/talk")
    with BagReader([ROS2 / "talker_mcap"]) as reader:
        stamps = [stamp for _c, stamp, _raw in reader.messages(reader.select(["/topic"]))]
    clock = Watched(
        rostool_popen(["topic", "echo", "/clock", "rosgraph_msgs/msg/Clock", "--json"], graph_env)
    )
    try:
        play = [
            "--ros2", "bag", "play", str(ROS2 / "talker_mcap"), "--topics", "/topic /rosout",
            "--exclude-topics", "/rosout", "--remap", "/topic:=/talk /rosout:=/log",
            "--clock-topics", "/topic", "-d", "2",
        ]  # fmt: skip
        result = rostool(play, graph_env, timeout=60)
        assert result.returncode == 0, result.stderr
        assert wait_until(lambda: len(listener.of("heard")) >= 10, timeout=10)
        clock.wait_for(
            lambda text: sum(line.startswith("{") for line in text.splitlines()) >= len(stamps), 10
        )
    finally:
        out, _err = clock.stop()
    assert [e["data"] for e in listener.of("heard")] == [f"Hello, world! {i}" for i in range(10)]
    import json

    clocks = [json.loads(line)["clock"] for line in out.splitlines() if line.startswith("{")]
    assert [c["sec"] * 10**9 + c["nanosec"] for c in clocks] == stamps


QOS_PROFILE = """/test_topic:
  history: keep_all
  depth: 0
  reliability: reliable
  durability: transient_local
  deadline:
    sec: 0
    nsec: 0
  lifespan:
    sec: 0
    nsec: 0
  liveliness: automatic
  liveliness_lease_duration:
    sec: 0
    nsec: 0
  avoid_ros_namespace_conventions: false
"""


@pytest.mark.parametrize(
    ("profile", "error"),
    [
        (QOS_PROFILE, None),  # test_qos_simple
        ("/test_topic:\n  history: keep_all\n  durability: volatile\n", None),  # test_incomplete_qos_profile
        (  # test_incomplete_qos_duration
            "/test_topic:\n  history: keep_all\n  depth: 0\n  reliability: reliable\n  durability: volatile\n"
            "  deadline:\n    sec: 2\n",
            "Time overrides must include both",
        ),
        ("/test_topic:\n  foo: bar\n", "unknown QoS policy 'foo'"),  # test_api: interpret_dict invalid
        (  # test_api test_convert_yaml_to_qos_profile: two topics, each its own fields
            "/topic1: {history: keep_all, durability: volatile, reliability: reliable}\n"
            "/topic2: {history: keep_all, avoid_ros_namespace_conventions: false}\n",
            None,
        ),
    ],
)
def test_record_qos_profile_overrides(profile: str, error: str | None, tmp_path: Path) -> None:
    """ros2bag test_record_qos_profiles.py: `record -a --qos-profile-overrides-path FILE --output DIR`."""
    path = tmp_path / "qos.yaml"
    path.write_text(profile)
    args = ["--ros2", "bag", "record", "-a", "--qos-profile-overrides-path", str(path), "--output", "out"]
    result = rostool([*args, "--duration", "1"], ros2_env(), cwd=tmp_path)
    if error is None:
        assert result.returncode == 0 and (tmp_path / "out" / "metadata.yaml").exists(), result.stderr
    else:
        assert result.returncode != 0 and error in result.stderr and result.stderr.count("\n") == 1


def test_record_nonexistent_qos_profile_is_refused(tmp_path: Path) -> None:
    """test_nonexistent_qos_profile: the argument names a file that does not exist."""
    args = ["--ros2", "bag", "record", "-a", "--qos-profile-overrides-path", str(tmp_path / "foobar.yaml")]
    result = rostool(args, ros2_env(), cwd=tmp_path)
    assert result.returncode != 0 and "--qos-profile-overrides-path" in result.stderr
    assert "does not exist" in result.stderr and not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "profile", [QOS_PROFILE, "/test_topic:\n  history: keep_all\n  durability: volatile\n"]
)
def test_play_qos_profile_overrides_on_the_empty_bag(profile: str, tmp_path: Path) -> None:
    """ros2bag test_play_qos_profiles.py: `play --qos-profile-overrides-path FILE empty_bag`: no error."""
    path = tmp_path / "qos.yaml"
    path.write_text(profile)
    args = [
        "--ros2",
        "bag",
        "play",
        "--qos-profile-overrides-path",
        str(path),
        str(ROS2 / "empty_bag_sqlite3"),
    ]
    result = rostool(args, ros2_env(), timeout=20)
    assert result.returncode == 0 and "rostool: warning: no message was played" in result.stderr
    assert "Traceback" not in result.stderr and "error" not in result.stderr.lower()


def test_recording_killed_is_recovered_by_reindex(
    start_peer: Peer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """kill -9 while recording a rosbag2 directory: `bag reindex DIR` gives a bag rosbags reads."""
    talker = start_peer("--talk", "/chatter", "--rate", "50")
    started = time.monotonic()
    proc = rostool_popen(
        ["--ros2", "bag", "record", "--topics", "/chatter", "-o", "killed"], graph_env, cwd=tmp_path
    )
    # killed once the talker has seen the recorder subscribe and published 50 more (1 s at 50 Hz)
    matched = talker.wait_for("matched", lambda e: e["subscribers"] > 0 and e["t"] > started, 60)
    talker.wait_for(matched["progress"], lambda e: e["count"] >= matched["count"] + 50, 60)
    proc.kill()
    proc.communicate(timeout=10)
    bag = tmp_path / "killed"
    assert (bag / "killed_0.mcap").exists()
    fixed = rostool(["bag", "reindex", str(bag)], graph_env)
    assert fixed.returncode == 0, fixed.stderr
    messages = read_rosbags(bag)["/chatter"]
    assert messages and all(m.data.startswith("hello") for m in messages)  # type: ignore[attr-defined]
