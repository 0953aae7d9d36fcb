"""`bag play` into a ROS 2 graph, checked with `topic echo`: rosbag2 recordings' CDR bytes as they are,
ROS 1 bags converted as `bag convert` converts them, and /clock."""

from __future__ import annotations

import json
import time
from pathlib import Path

from tests.support import TESTDATA, rostool, rostool_popen, stop
from tests.test_ros2_graph import ros2_env, yaml_docs

TALKER = TESTDATA / "ros2" / "talker_mcap"
EXAMPLE = TESTDATA / "ros1" / "example.bag"
EXAMPLE_START_NS, EXAMPLE_END_NS = 1396293887_844783943, 1396293909_544870199  # its first and last message


def test_ros2_bag_plays_into_ros2() -> None:
    env = ros2_env()
    env.pop("ROS_VERSION")  # --ros2 selects the graph
    echo = rostool_popen(["--ros2", "topic", "echo", "/topic"], env)
    try:
        only_topic = ["--topics", "/topic", "--wait-for-subscribers"]
        played = rostool(["--ros2", "bag", "play", "-r", "5", *only_topic, str(TALKER)], env)
        assert played.returncode == 0, played.stderr
        assert played.stderr == ""
        time.sleep(0.5)
    finally:
        out, err = stop(echo)
    assert yaml_docs(out) == [f"data: Hello, world! {i}" for i in range(10)], err

    # the whole bag: /rosout's rcl_interfaces/msg/Log plays too (no ROS 1 conversion involved)
    rosout = rostool_popen(["--ros2", "topic", "echo", "/rosout", "--json"], env)
    try:
        played = rostool(["--ros2", "bag", "play", "--immediate", "-d", "1", str(TALKER)], env)
        assert played.returncode == 0, played.stderr
        time.sleep(0.5)
    finally:
        out, err = stop(rosout)
    assert "Publishing: 'Hello, world! 0'" in out, err


def json_lines(text: str) -> list[dict[str, object]]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def without_seq(message: object) -> object:
    """A ROS 1 message as ROS 2 has it: std_msgs/Header without `seq`, Time as sec/nanosec."""
    if isinstance(message, list):
        return [without_seq(item) for item in message]
    if not isinstance(message, dict):
        return message
    if set(message) == {"secs", "nsecs"}:
        return {"sec": message["secs"], "nanosec": message["nsecs"]}
    return {key: without_seq(value) for key, value in message.items() if key != "seq"}


def example_messages(topics: list[str], seconds: float = float("inf")) -> dict[str, list[object]]:
    """`bag echo`'s messages of example.bag's first `seconds`, by topic, as they should arrive in ROS 2."""
    echoed = rostool(["bag", "echo", str(EXAMPLE), *topics, "--json"], ros2_env())
    assert echoed.returncode == 0, echoed.stderr
    lines = json_lines(echoed.stdout)
    if len(topics) == 1:  # bare messages, without topic and time
        lines = [{"topic": topics[0], "t": 0.0, "msg": message} for message in lines]
    end = EXAMPLE_START_NS / 1e9 + seconds
    found: dict[str, list[object]] = {topic: [] for topic in topics}
    for line in lines:
        if float(line["t"]) < end:  # type: ignore[arg-type]
            found[str(line["topic"])].append(without_seq(line["msg"]))
    return found


def test_ros1_bag_plays_into_ros2_converted() -> None:
    env = ros2_env()
    topics = ["/tf", "/turtle1/cmd_vel"]
    expected = example_messages(topics, seconds=3)  # played: 3 s of bag time at double speed
    assert len(expected["/tf"]) > 300 and len(expected["/turtle1/cmd_vel"]) > 30
    echoes = {
        topic: rostool_popen(["topic", "echo", topic, "--json", "-n", str(len(expected[topic]))], env)
        for topic in topics
    }
    try:
        window = ["-r", "2", "-u", "3", "--wait-for-subscribers"]
        played = rostool(["bag", "play", *window, str(EXAMPLE), "--topics", *topics], env, timeout=60)
        assert played.returncode == 0, played.stderr
        assert played.stderr == ""
        # -n: each echo ends after the last message; communicate reads its pipe so that it can print them
        received = {topic: echo.communicate(timeout=30) for topic, echo in echoes.items()}
    finally:
        for echo in echoes.values():
            if echo.poll() is None:
                stop(echo)
    # tf/tfMessage arrives as tf2_msgs/msg/TFMessage with ROS 2's Header (no seq), values unchanged
    tf = json_lines(received["/tf"][0])
    assert tf == expected["/tf"], received["/tf"][1]
    assert tf[0]["transforms"][0]["header"] == {  # type: ignore[index]
        "stamp": {"sec": 1396293888, "nanosec": 56065082},
        "frame_id": "world",
    }
    cmd_vel = json_lines(received["/turtle1/cmd_vel"][0])
    assert cmd_vel == expected["/turtle1/cmd_vel"], received["/turtle1/cmd_vel"][1]
    assert cmd_vel[0] == {"linear": {"x": 2.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}

    # types ROS 2 lacks (rosgraph_msgs/Log, turtlesim/Pose, turtlesim/Color) play as converted, no warning
    whole = rostool(["bag", "play", "--immediate", "-d", "0", str(EXAMPLE)], env, timeout=60)
    assert (whole.returncode, whole.stderr) == (0, "")


def test_latched_ros1_topic_is_transient_local_in_ros2() -> None:
    env = ros2_env()
    player = rostool_popen(["bag", "play", "--immediate", "-k", str(EXAMPLE), "--topics", "/tf_static"], env)
    try:
        time.sleep(2)  # played and kept alive: only a transient_local writer still has the message
        late = rostool(["topic", "echo", "/tf_static", "-n", "1", "--json", "--timeout", "20"], env)
    finally:
        stop(player)
    assert late.returncode == 0, late.stderr
    assert json_lines(late.stdout) == example_messages(["/tf_static"])["/tf_static"]


def test_clock_carries_increasing_bag_time() -> None:
    env = ros2_env()
    clock = rostool_popen(["topic", "echo", "/clock", "--json"], env)
    try:
        time.sleep(1)  # the echo has to be running before /clock is advertised (it is not latched)
        played = rostool(["bag", "play", "--clock", "--hz", "40", "-u", "2", str(EXAMPLE)], env, timeout=60)
        assert played.returncode == 0, played.stderr
        assert played.stderr == ""
        time.sleep(0.5)
    finally:
        out, err = stop(clock)
    messages = json_lines(out)
    assert all(set(m) == {"clock"} for m in messages), out
    stamps = [m["clock"]["sec"] * 1_000_000_000 + m["clock"]["nanosec"] for m in messages]  # type: ignore[index]
    assert len(stamps) >= 10, err  # 2 s at 40 Hz; no timing assert, only that it ticks while playing
    assert all(EXAMPLE_START_NS <= stamp <= EXAMPLE_END_NS for stamp in stamps), stamps
    assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps), stamps


def test_ros1_type_laid_out_differently_in_ros2_is_skipped(tmp_path: Path) -> None:
    """As ROS 2 bags' types without a ROS 1 twin are skipped in ROS 1 play: a warning, no traceback."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    from rostool.interfaces.fill import build_message

    store = get_typestore(Stores.ROS1_NOETIC)
    marker_type = "visualization_msgs/msg/Marker"  # ROS 2's has texture and mesh_file fields ROS 1's lacks
    marker = build_message(store, marker_type, {"header": {"frame_id": "map"}, "text": "hello"})
    bag = tmp_path / "marker.bag"
    with Writer(bag) as writer:
        conn = writer.add_connection("/marker", marker_type, typestore=store)
        writer.write(conn, 1_000_000_000, store.serialize_ros1(marker, marker_type))
    env = ros2_env()
    played = rostool(["bag", "play", "-d", "0", str(bag)], env)
    assert played.returncode == 0, played.stderr
    assert played.stderr.splitlines() == [
        "rostool: warning: skipping /marker: visualization_msgs/msg/Marker is laid out differently in ROS 2",
        "rostool: warning: no message was played (check --start-offset and --topics)",
    ]

    missing = rostool(["bag", "play", str(EXAMPLE), "--topics", "/nothing"], env)
    assert missing.returncode == 1 and missing.stderr.count("\n") == 1
    assert missing.stderr.startswith("rostool: topic /nothing is not in the bag"), missing.stderr
