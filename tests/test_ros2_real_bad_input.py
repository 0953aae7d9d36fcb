"""Bad input against a real rclpy graph (Jazzy and Kilted, Fast DDS): unknown names, a wrong service type,
a peer that vanishes mid-call. Each ends in one line on stderr and a non-zero exit, never a hang."""

from __future__ import annotations

import signal
import time
from collections.abc import Callable

from tests.ros2_peers import RclpyPeer
from tests.support import rostool, rostool_popen
from tests.test_ros2_fastdds_rpc import in_lanes

Start = Callable[..., RclpyPeer]


PROGRESS = "Waiting for an action server to become available..."  # ros2 action send_goal's note, kept


def error_lines(stderr: str) -> list[str]:
    return [line for line in stderr.strip().splitlines() if line != PROGRESS]


def one_line_failure(args: list[str], env: dict[str, str], words: str, timeout: float = 30) -> None:
    done = rostool(args, env, timeout=timeout)
    assert done.returncode != 0, (args, done.stdout)
    lines = error_lines(done.stderr)
    assert len(lines) == 1 and words in lines[0], (args, done.stderr)


def test_unknown_names_and_a_wrong_service_type(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "server", "--service", "/set_flag", "--action", "/fibonacci", "--params")
    cases = [
        (["service", "call", "/set_flag", "std_srvs/srv/Trigger", "{}", "--timeout", "3"],
         "service /set_flag has type std_srvs/srv/SetBool, not std_srvs/srv/Trigger"),
        (["service", "call", "/nope", "std_srvs/srv/Trigger", "{}", "--timeout", "3"], "/nope"),
        (["service", "type", "/nope"], "/nope"),
        (["action", "info", "/nope"], "unknown action /nope"),
        (["action", "send-goal", "/nope", "test_msgs/action/Fibonacci", "{order: 3}", "--timeout", "3"],
         "/nope"),
        (["param", "get", "/nobody", "speed"], "/nobody"),
        (["param", "get", "/server", "no_such_parameter"], "no_such_parameter"),
        (["param", "set", "/server", "speed", "not a number"], "speed"),
    ]  # fmt: skip
    # side by side, except the two runs that call /server's parameter services: one lane, one after the
    # other (rostool's DDS client takes the first reply after its request, see in_lanes)
    lanes = [("/server" if args[2] == "/server" and args[0] == "param" else None, [str(index)])
             for index, (args, _words) in enumerate(cases)]  # fmt: skip
    in_lanes(lambda index: one_line_failure(cases[int(index[0])][0], graph_env, cases[int(index[0])][1]),
             lanes, workers=3)  # fmt: skip


def test_a_server_that_vanishes_mid_goal(graph_env: dict[str, str], start_peer: Start) -> None:
    """SIGKILL leaves no goodbye: the client notices when the server's participant lease ends (Fast DDS's
    default 20 s; 3 s here) and says which call lost its server."""
    server = start_peer("--name", "server", "--action", "/fibonacci", "--step", "1.0", lease=3)
    goal = rostool_popen(["action", "send-goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 30}"],
                         graph_env)  # fmt: skip
    server.wait_for("goal", timeout=20)
    server.proc.send_signal(signal.SIGKILL)
    started = time.monotonic()
    _out, err = goal.communicate(timeout=60)
    assert goal.returncode == 1
    lines = error_lines(err)
    assert len(lines) == 1 and "went away" in lines[0], err
    assert time.monotonic() - started < 40
