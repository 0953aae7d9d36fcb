"""`topic hz` when the publisher stops: rostopic's "no new messages" under ROS 1 (not the last average
again), and no further report line under ROS 2, as ros2 topic hz does; against real publishers."""

from __future__ import annotations

from collections.abc import Callable

from tests.ros2_peers import RclpyPeer
from tests.support import Watched, debian_popen, rostool_popen, stop


def test_ros1_hz_says_no_new_messages_once_the_publisher_stops(debian_master: dict[str, str]) -> None:
    env = debian_master
    publisher = debian_popen(["rostopic", "pub", "-r", "20", "/beat", "std_msgs/String", "data: x"], env)
    hz = Watched(rostool_popen(["--ros1", "topic", "hz", "/beat"], env))
    try:
        assert hz.wait_for(lambda out: "average rate" in out, 30), hz.stdout
        stop(publisher)
        assert hz.wait_for(lambda out: out.count("no new messages") >= 2, 15), hz.stdout
        silent = hz.stdout.split("no new messages", 1)[1]
        assert "average rate" not in silent, hz.stdout  # once silent, the old average is not repeated
    finally:
        stop(publisher)
        stop(hz.proc)


def test_ros2_hz_prints_nothing_new_once_the_publisher_stops(
    start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]
) -> None:
    peer = start_peer("--name", "beat", "--talk", "/beat", "--rate", "20")
    hz = Watched(rostool_popen(["--ros2", "topic", "hz", "/beat"], graph_env))
    try:
        assert hz.wait_for(lambda out: out.count("average rate") >= 2, 30), hz.stdout
        peer.stop()
        reports = hz.stdout.count("average rate")
        # the window drains within a report or two, then nothing: give it 4 s of silence
        assert not hz.wait_for(lambda out: out.count("average rate") > reports + 2, 4), hz.stdout
        settled = hz.stdout.count("average rate")
        assert not hz.wait_for(lambda out: out.count("average rate") > settled, 3), hz.stdout
        assert "no new messages" not in hz.stdout
    finally:
        stop(hz.proc)
