"""The one rule for flags: rostopic's forms under --ros1, ros2cli's under --ros2, each checked against real
peers (Debian's rosmaster and rostopic; an rclpy talker/listener of each distro)."""

from __future__ import annotations

import xmlrpc.client
from collections.abc import Callable

from tests.ros2_peers import RclpyPeer
from tests.support import debian, rostool, rostool_popen, stop, wait_until


def test_ros1_takes_rostopics_forms(debian_master: dict[str, str]) -> None:
    """`topic pub -r HZ` publishes repeatedly and `topic echo -n 1` stops after one message, as rostopic's
    do; the real rostopic echo reads the same message."""
    env = debian_master
    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    publisher = rostool_popen(
        ["--ros1", "topic", "pub", "/rule", "std_msgs/String", "data: one", "-r", "2"], env
    )
    try:
        published = lambda: ["/rule", "std_msgs/String"] in master.getPublishedTopics("/t", "")[2]  # noqa: E731
        assert wait_until(published, 30)
        ours = rostool(["--ros1", "topic", "echo", "-n", "1", "/rule"], env, timeout=60)
        theirs = debian(["rostopic", "echo", "-n", "1", "/rule"], env, timeout=60)
        assert ours.returncode == 0, ours.stderr
        assert ours.stdout == theirs.stdout == 'data: "one"\n---\n'
    finally:
        stop(publisher)


def test_ros2_takes_ros2clis_forms(graph_env: dict[str, str], start_peer: Callable[..., RclpyPeer]) -> None:
    """`topic echo --once` and `topic pub -t N` (with -w, ros2cli's wait for subscriptions) under --ros2."""
    peer = start_peer("--talk", "/chatter", "--listen", "/heard")
    echo = rostool(["--ros2", "topic", "echo", "--once", "/chatter"], graph_env, timeout=60)
    assert echo.returncode == 0, echo.stderr
    lines = echo.stdout.splitlines()
    assert lines[0].startswith("data: hello ") and lines[1:] == ["---"]

    pub = rostool(["--ros2", "topic", "pub", "-t", "1", "-w", "1", "/heard", "std_msgs/msg/String",
                   "{data: rule}"], graph_env, timeout=60)  # fmt: skip
    assert pub.returncode == 0, pub.stderr
    # ros2's waiting line comes only when the subscription has not matched at the first look (nearly always)
    waiting = "Waiting for at least 1 matching subscription(s)..."
    assert [line for line in pub.stdout.splitlines() if line != waiting] == [
        "publisher: beginning loop", "publishing #1: std_msgs.msg.String(data='rule')", "",
    ]  # fmt: skip
    peer.wait_for("heard", lambda e: e["topic"] == "/heard" and e["data"] == "rule", timeout=20)
