"""rostool's own DDS (Cyclone) with a localhost discovery range listens on 127.0.0.1 only, and still talks to
real rclpy nodes on Fast DDS both ways: a real subscriber hears rostool's publisher, rostool's echo hears a
real talker."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from tests.ros2_peers import RclpyPeer, assert_loopback_only, bound_addresses
from tests.support import rostool_popen, stop, wait_until


def test_dds_backend_binds_loopback_only_and_is_heard(
    start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str], tmp_path: Path
) -> None:
    peer = start_peer("--name", "bound", "--talk", "/spoken", "--listen", "/heard")
    env = {**graph_env, "ROSTOOL_ROS2_BACKEND": "dds"}
    publisher = rostool_popen(
        ["--ros2", "topic", "pub", "/heard", "std_msgs/msg/String", "data: hi", "-r", "10"], env
    )
    echo = rostool_popen(["--ros2", "topic", "echo", "/spoken", "--once"], env)
    try:
        assert peer.wait_for("heard", lambda e: e["data"] == "hi", timeout=30)
        addresses = bound_addresses(publisher.pid)
        assert wait_until(lambda: echo.poll() is not None, 30), "rostool's echo heard nothing from the talker"
        out, _err = echo.communicate()
    finally:
        stop(publisher)
        stop(echo)
    assert addresses, "the publisher had no socket open"
    assert_loopback_only(addresses)
    assert "data: hello" in out
