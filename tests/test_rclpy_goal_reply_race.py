"""The rclpy backend's `action send_goal` never loses the server's reply to its own registration.

Jazzy's rclpy ActionClient sends a goal (or result) request and only then registers the future of its
reply, without a lock; when the executor's thread takes the reply in between, rclpy drops it as unexpected
and the goal waits forever (seen in CI under load: `send_goal` timed out three times in a row against a
real server that the real `ros2` reached at the same moment). Here the window is widened on purpose: the
client's request calls pause 0.3 s after sending, which is longer than a real server takes to reply on
loopback. rostool must still print the goal's result, against a real rclpy action server, on both distros.
"""

from __future__ import annotations

import subprocess
from collections.abc import Callable
from pathlib import Path

from tests.ros2_peers import RclpyPeer, peer_env, peer_python

# rostool run in-process by the peer venv's Python, with rclpy's ActionClient request handle wrapped: every
# goal and result request pauses after it is sent, as a preempted sender would
WIDENED = r"""
import sys, time
import rclpy.action
from rclpy.action import ActionClient

class PausingHandle:
    def __init__(self, handle):
        self._handle = handle
    def __getattr__(self, name):
        return getattr(self._handle, name)
    def __enter__(self):
        return self._handle.__enter__()
    def __exit__(self, *details):
        return self._handle.__exit__(*details)
    def send_goal_request(self, request):
        number = self._handle.send_goal_request(request)
        time.sleep(0.3)
        return number
    def send_result_request(self, request):
        number = self._handle.send_result_request(request)
        time.sleep(0.3)
        return number

class WidenedClient(ActionClient):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._client_handle = PausingHandle(self._client_handle)

rclpy.action.ActionClient = WidenedClient
from rostool.cli import main
sys.argv = ["rostool", "--ros2-backend", "rclpy", *sys.argv[1:]]
main()
"""


def test_goal_and_result_replies_are_never_dropped(
    distro: str,
    graph_env: dict[str, str],
    tmp_path: Path,
    start_peer: Callable[..., RclpyPeer],
) -> None:
    start_peer("--name", "race_server", "--action", "/fibonacci")
    args = ["--ros2", "action", "send_goal", "--timeout", "20", "/fibonacci", "test_msgs/action/Fibonacci",
            "{order: 3}"]  # fmt: skip
    done = subprocess.run(
        [str(peer_python(distro)), "-c", WIDENED, *args],
        env=peer_env(graph_env, tmp_path),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Ignoring unexpected" not in done.stderr
    # the real server's Fibonacci of order 3, as rostool prints ros2cli's form
    assert "Goal accepted with ID:" in done.stdout
    assert "Result:\n    sequence:\n- 0\n- 1\n- 1\n- 2\n" in done.stdout
    assert "Goal finished with status: SUCCEEDED" in done.stdout
