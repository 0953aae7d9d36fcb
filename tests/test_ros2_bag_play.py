"""`bag play` into a ROS 2 graph: a rosbag2 recording's CDR bytes, published unchanged, reach `topic echo`."""

from __future__ import annotations

import time

from tests.support import TESTDATA, rostool, rostool_popen, stop
from tests.test_ros2_graph import ros2_env, yaml_docs

TALKER = TESTDATA / "ros2" / "talker_mcap"


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
        played = rostool(["--ros2", "bag", "play", "-i", "-d", "1", str(TALKER)], env)
        assert played.returncode == 0, played.stderr
        time.sleep(0.5)
    finally:
        out, err = stop(rosout)
    assert "Publishing: 'Hello, world! 0'" in out, err


def test_ros2_play_refuses_ros1_bags_and_clock() -> None:
    env = ros2_env()
    ros1 = rostool(["bag", "play", str(TESTDATA / "ros1" / "example.bag")], env)
    assert ros1.returncode == 1 and ros1.stderr.count("\n") == 1
    assert "nothing to play in ROS 2: no ROS 2 bag topics selected" in ros1.stderr
    clock = rostool(["bag", "play", "--clock", str(TALKER)], env)
    assert clock.returncode == 1
    assert clock.stderr == "rostool: --clock applies to ROS 1 graphs only in this rostool version\n"
