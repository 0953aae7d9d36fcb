"""Issue 25: `bag burst` (ros2 bag burst's flags): exactly N messages, from --start-offset, as fast as they
go, received by a real subscriber (rostool's echo under ROS 2, Debian's rostopic echo under ROS 1); the
expected messages are read from the bag with rosbags."""

from __future__ import annotations

import json
from pathlib import Path

from tests.support import TESTDATA, Watched, debian_popen, ros2_env, rostool, rostool_popen

TALKER = TESTDATA / "ros2" / "talker_mcap"
EXAMPLE = TESTDATA / "ros1" / "example.bag"


def bag_strings(bag: Path, topic: str, offset: float = 0.0) -> list[str]:
    """The `data` of `topic`'s std_msgs/String messages from `offset` seconds after the bag's start."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        start = reader.start_time + round(offset * 1e9)
        conns = [c for c in reader.connections if c.topic == topic]
        return [
            reader.deserialize(data, conn.msgtype).data
            for conn, stamp, data in reader.messages(connections=conns)
            if stamp >= start
        ]


def test_burst_publishes_exactly_n_messages_from_the_offset() -> None:
    env = ros2_env()
    expected = bag_strings(TALKER / "talker.mcap", "/topic", offset=2.5)[:3]  # rosbags reads the file
    assert len(expected) == 3 and expected[0] != "Hello, world! 0"
    echo = Watched(rostool_popen(["--ros2", "topic", "echo", "/topic", "--json"], env))
    try:
        burst = ["--ros2", "bag", "burst", str(TALKER), "-n", "3", "--start-offset", "2.5"]
        done = rostool([*burst, "--topics", "/topic", "--wait-for-subscribers"], env)
        assert done.returncode == 0, done.stderr
        assert done.stderr == "Burst 3 messages.\n"
        assert echo.wait_for(lambda out: out.count("\n") >= 3, 10), echo.stdout
    finally:
        out, _err = echo.stop()
    assert [json.loads(line)["data"] for line in out.splitlines()] == expected


def test_burst_all_messages_into_ros1(debian_master: dict[str, str]) -> None:
    env = debian_master
    echo = Watched(debian_popen(["rostopic", "echo", "/turtle1/cmd_vel/linear/x"], env))
    try:
        done = rostool(["--ros1", "bag", "burst", str(EXAMPLE), "--topics", "/turtle1/cmd_vel",
                        "--wait-for-subscribers"], env, timeout=60)  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert done.stderr == "Burst 357 messages.\n"  # rosbag info: /turtle1/cmd_vel 357 msgs
        assert echo.wait_for(lambda out: out.count("---") >= 357, 20), echo.stdout[-300:]
    finally:
        echo.stop()
