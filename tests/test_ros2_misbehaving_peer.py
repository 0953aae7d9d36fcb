"""A participant that announces garbage discovery data (tests/liar_peer.py) beside a real rclpy node: the DDS
backend's listings still answer, exit 0 and list the real node; nothing of the garbage is listed and nothing
crashes (no internal error)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from tests.ros2_peers import RclpyPeer
from tests.support import Watched, rostool, stop

LIAR = Path(__file__).resolve().parent / "liar_peer.py"


def test_listings_survive_a_participant_that_lies(
    start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]
) -> None:
    start_peer("--name", "honest", "--talk", "/honest_chatter")
    env = {**graph_env, "ROSTOOL_ROS2_BACKEND": "dds"}
    liar = Watched(
        subprocess.Popen(
            [sys.executable, str(LIAR)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
    )
    try:
        assert liar.wait_for(lambda out: "ready" in out, 30), liar.proc.stderr
        for args, expect in (
            (["node", "list"], "/honest"),
            (["topic", "list", "-t"], "/honest_chatter [std_msgs/msg/String]"),
            (["node", "info", "/honest"], "/honest_chatter: std_msgs/msg/String"),
            (["service", "list"], "/honest/list_parameters"),
        ):
            done = rostool(["--ros2", *args], env, timeout=60)
            assert done.returncode == 0, (args, done.stderr)
            assert expect in done.stdout, (args, done.stdout)
            assert "internal error" not in done.stderr and "Traceback" not in done.stderr, done.stderr
            assert "not_ros" not in done.stdout and "nnnn" not in done.stdout
        assert liar.proc.poll() is None, "the liar stopped lying early: " + liar.proc.stderr.read()  # type: ignore[union-attr]
    finally:
        stop(liar.proc)
