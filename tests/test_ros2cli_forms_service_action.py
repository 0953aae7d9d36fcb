# ruff: noqa: E501  (expected ros2cli lines are kept whole)
"""ros2cli's own ros2service and ros2action test cases, run against rostool and real rclpy peers.

Command lines and expected output lines are those of ros2cli's tests (ros2service/test/test_cli.py and
test_echo.py, ros2action/test/test_cli.py), taken as facts; the graphs are rebuilt from tests/rclpy_peer.py:
/my_ns/echo_server serving test_msgs/srv/BasicTypes on /my_ns/echo (its request echoed back),
/my_ns/_hidden_echo_server on /my_ns/_echo, and /fibonacci_action_server serving test_msgs/action/Fibonacci
on /fibonacci. rclpy's own repr of the request and response, computed by the peer's interpreter, is the
referee of `service call`'s lines. rostool finds test_msgs' .srv files through AMENT_PREFIX_PATH, as a
sourced ROS 2 install gives it. Since Jazzy every node also serves ~/get_type_description, one more
service per node than ros2cli's expectations count.
"""

from __future__ import annotations

import re
import subprocess
from collections.abc import Iterator
from typing import Any

import pytest

from tests.ros2_peers import PEERS_DIR, RclpyPeer, StartPeer, WarmDaemon, peer_python, serving
from tests.support import Watched, rostool, rostool_popen, wait_until
from tests.test_ros2cli_forms import Cases, Start, side_by_side

PARAMETER_SERVICES = 6


def ros2(env: dict[str, str], *args: str, timeout: float = 40) -> Any:
    return rostool(["--ros2", *args], env, timeout=timeout)


def echo_call_output(distro: str, **fields: Any) -> list[str]:
    """ros2cli's get_echo_call_output, with rclpy's repr from the peer's own interpreter."""
    script = (
        "import sys, json\nfrom test_msgs.srv import BasicTypes\n"
        "fields = json.loads(sys.argv[1])\n"
        "print(repr(BasicTypes.Request(**fields)))\nprint(repr(BasicTypes.Response(**fields)))\n"
    )
    import json

    done = subprocess.run([str(peer_python(distro)), "-c", script, json.dumps(fields)], capture_output=True,
                          text=True, check=True, env={"PATH": "/usr/bin:/bin"})  # fmt: skip
    request, response = done.stdout.splitlines()
    return [f"requester: making request: {request}", "", "response:", response, ""]


@pytest.fixture
def service_env(graph_env: dict[str, str], distro: str) -> dict[str, str]:
    return {**graph_env, "AMENT_PREFIX_PATH": str(PEERS_DIR / distro)}


@pytest.fixture
def service_daemon(service_env: dict[str, str]) -> Iterator[WarmDaemon]:
    """A warm graph daemon of service_env's own (its key includes AMENT_PREFIX_PATH), stopped at the end."""
    with serving(service_env) as daemon:
        yield daemon


@pytest.fixture
def echo_servers(service_daemon: WarmDaemon, start_peer: StartPeer) -> list[RclpyPeer]:
    peers = start_peer.together(
        ["--name", "echo_server", "--namespace", "/my_ns", "--echo-service", "echo"],
        ["--name", "_hidden_echo_server", "--namespace", "/my_ns", "--echo-service", "_echo"],
    )
    service_daemon.ready()
    # the daemon knows both servers' nodes (names come after the endpoints)
    assert wait_until(lambda: service_daemon.graph_size()["nodes"] == len(peers), timeout=20)
    return peers


def node_services(node: str, with_types: bool = False) -> list[re.Pattern[str]]:
    kind = r" \[rcl_interfaces/srv/.*Parameter.*\]" if with_types else ""
    return [re.compile(rf"{node}/get_type_description")] + [
        re.compile(rf"{node}/.*parameter.*{kind}") for _ in range(PARAMETER_SERVICES)
    ]


def lines_match(lines: list[str], expected: list[Any]) -> bool:
    """launch_testing's strict expect_output: as many lines, each equal or matching its pattern (the
    node's services in any order)."""
    if len(lines) != len(expected):
        return False
    literal = [e for e in expected if isinstance(e, str)]
    if [line for line in lines if line in literal] != literal:
        return False
    rest = [line for line in lines if line not in literal]
    patterns = [e for e in expected if not isinstance(e, str)]
    return all(any(p.fullmatch(line) for p in patterns) for line in rest)


@pytest.mark.parametrize("distro", ["jazzy"])
def test_service_cases(distro: str, service_daemon: WarmDaemon, echo_servers: list[RclpyPeer]) -> None:
    """The listings side by side (they change nothing), then the calls one after the other (rostool's DDS
    client of a Fast DDS server takes the first reply after its request: rostool/graph/ros2/services.py)."""
    env, c = service_daemon.env, Cases()
    listed = side_by_side(
        env, ("service", "list"), ("service", "list", "--include-hidden-services"), ("service", "list", "-t"),
        ("service", "list", "-c"), ("service", "find", "test_msgs/srv/BasicTypes"),
        ("service", "find", "--include-hidden-services", "test_msgs/srv/BasicTypes"),
        ("service", "find", "-c", "test_msgs/srv/BasicTypes"), ("service", "find", "not_a_service_type"),
        ("service", "type", "/my_ns/echo"), ("service", "type", "/not_a_service"), ("service", "info", "/my_ns/echo"),
        ("service", "list", "--no-daemon", "--spin-time", "1", "-s"),
    )  # fmt: skip
    out = listed("service", "list").stdout.splitlines()
    c.check(
        "test_list_services", lines_match(out, ["/my_ns/echo", *node_services("/my_ns/echo_server")]), out
    )
    out = listed("service", "list", "--include-hidden-services").stdout.splitlines()
    c.check("test_list_hidden", lines_match(out, ["/my_ns/_echo", *node_services("/my_ns/_hidden_echo_server"),
            "/my_ns/echo", *node_services("/my_ns/echo_server")]) and out[0] == "/my_ns/_echo", out)  # fmt: skip
    out = listed("service", "list", "-t").stdout.splitlines()
    c.check("test_list_with_types", "/my_ns/echo [test_msgs/srv/BasicTypes]" in out and len(out) == 8
            and sum(bool(re.fullmatch(r"/my_ns/echo_server/.*parameter.* \[rcl_interfaces/srv/.*Parameter.*\]", x))
                    for x in out) == PARAMETER_SERVICES, out)  # fmt: skip
    out = listed("service", "list", "-c").stdout.splitlines()
    c.check("test_list_count (7 + get_type_description)", out == ["8"], out)
    out = listed("service", "find", "test_msgs/srv/BasicTypes").stdout
    c.check("test_find", out == "/my_ns/echo\n", out)
    out = listed("service", "find", "--include-hidden-services", "test_msgs/srv/BasicTypes").stdout
    c.check("test_find_hidden", out == "/my_ns/_echo\n/my_ns/echo\n", out)
    out = listed("service", "find", "-c", "test_msgs/srv/BasicTypes").stdout
    c.check("test_find_count", out == "1\n", out)
    got = listed("service", "find", "not_a_service_type")
    c.check("test_find_not_a_service_type", got.returncode == 0 and got.stdout == "", got)
    out = listed("service", "type", "/my_ns/echo").stdout
    c.check("test_type", out == "test_msgs/srv/BasicTypes\n", out)
    got = listed("service", "type", "/not_a_service")
    c.check("test_type_on_not_a_service", got.returncode == 1 and got.stdout == "", got)
    got = ros2(env, "service", "call", "/my_ns/echo", "test_msgs/srv/BasicTypes")
    c.check(
        "test_call_no_args", got.returncode == 0 and got.stdout.splitlines() == echo_call_output(distro), got
    )
    values = "{bool_value: false, int32_value: -1, float64_value: 0.1, string_value: bazbar}"
    got = ros2(env, "service", "call", "/my_ns/echo", "test_msgs/srv/BasicTypes", values)
    expected = echo_call_output(
        distro, bool_value=False, int32_value=-1, float64_value=0.1, string_value="bazbar"
    )
    c.check("test_call", got.returncode == 0 and got.stdout.splitlines() == expected, got)
    values = "{bool_value: true, int32_value: 1, float64_value: 1.0, string_value: foobar}"
    expected = echo_call_output(
        distro, bool_value=True, int32_value=1, float64_value=1.0, string_value="foobar"
    )
    repeated = Watched(rostool_popen(
        ["--ros2", "service", "call", "-r", "1", "/my_ns/echo", "test_msgs/srv/BasicTypes", values], env
    ))  # fmt: skip
    repeated.wait_for(lambda out: len(out.splitlines()) >= 2 * len(expected), timeout=30)
    out, _err = repeated.stop()
    c.check("test_repeated_call", out.splitlines()[: 2 * len(expected)] == 2 * expected, out)
    out = listed("service", "info", "/my_ns/echo").stdout
    c.check(
        "service info (Jazzy+)",
        out == "Type: test_msgs/srv/BasicTypes\nClients count: 0\nServices count: 1\n",
        out,
    )
    got = listed("service", "list", "--no-daemon", "--spin-time", "1", "-s")
    c.check("accepted and ignored: service list --no-daemon --spin-time 1 -s", got.returncode == 0, got)
    c.done()


def echo_event(event: str, request: int, response: int) -> list[Any]:
    """One event of ros2cli's test_echo.py EXPECTED_OUTPUT."""
    return ["info:", f"  event_type: {event}", "  stamp:", re.compile(r"    sec: \d+"), re.compile(r"    nanosec: \d+"),
            "  client_gid: '<array type: uint8[16]>'", re.compile(r"  sequence_number: \d+"),
            f"request: '<sequence type: test_msgs/srv/BasicTypes_Request[1], length: {request}>'",
            f"response: '<sequence type: test_msgs/srv/BasicTypes_Response[1], length: {response}>'", "---"]  # fmt: skip


EXPECTED_ECHO = [*echo_event("REQUEST_SENT", 1, 0), *echo_event("REQUEST_RECEIVED", 1, 0),
                 *echo_event("RESPONSE_SENT", 0, 1), *echo_event("RESPONSE_RECEIVED", 0, 1)][:-1]  # fmt: skip


@pytest.mark.parametrize("distro", ["jazzy"])
def test_service_echo_no_arr(service_env: dict[str, str], start_peer: Start) -> None:
    """ros2cli's test_echo_no_arr: the four events of a call, in order, from the introspection topic."""
    start_peer("--name", "introspectable_service", "--echo-service", "test_introspectable", "--introspect")
    got = ros2(
        service_env, "service", "echo", "/test_introspectable", "--no-arr", "-n", "12", "--timeout", "15"
    )
    assert in_order(EXPECTED_ECHO, got.stdout.splitlines()), got


def fibonacci_send_goal_output(order: int, with_feedback: int = 0) -> list[Any]:
    """ros2cli's get_fibonacci_send_goal_output."""
    import yaml

    output: list[Any] = ["Waiting for an action server to become available...", "Sending goal:", f"     order: {order}",
                         "", re.compile("Goal accepted with ID: [a-f0-9]+"), ""]  # fmt: skip
    sequence = [0, 1]
    for _ in range(order - 1):
        sequence.append(sequence[-1] + sequence[-2])
        if with_feedback > 0:
            output += ["Feedback:", *("    " + yaml.dump({"sequence": sequence})).splitlines(), ""]
            with_feedback -= 1
    output += ["Result:", *("    " + yaml.dump({"sequence": sequence})).splitlines(), "",
               "Goal finished with status: SUCCEEDED"]  # fmt: skip
    return output


def matches(expected: Any, line: str) -> bool:
    return expected == line if isinstance(expected, str) else expected.fullmatch(line) is not None


def in_order(expected: list[Any], lines: list[str]) -> bool:
    """launch_testing's non-strict expect_output: the expected lines appear in order."""
    position = 0
    for line in lines:
        if position < len(expected) and matches(expected[position], line):
            position += 1
    return position == len(expected)


@pytest.mark.parametrize("distro", ["kilted"])
def test_action_cases(warm_daemon: WarmDaemon, start_peer: Start) -> None:
    env, c = warm_daemon.env, Cases()
    start_peer("--name", "fibonacci_action_server", "--action", "/fibonacci")
    warm_daemon.ready()
    assert wait_until(lambda: warm_daemon.graph_size()["actions"] == 1, timeout=20)
    # the reads side by side (they change nothing), the goals one after the other
    listed = side_by_side(
        env, ("action", "info", "/not_an_action"), ("action", "info", "/fibonacci"),
        ("action", "info", "-t", "/fibonacci"), ("action", "info", "-c", "/fibonacci"), ("action", "list"),
        ("action", "list", "-t"), ("action", "list", "-c"), ("action", "type", "/fibonacci"),
        ("action", "type", "/not_an_action"), ("action", "find", "test_msgs/action/Fibonacci"),
        ("action", "find", "-c", "test_msgs/action/Fibonacci"),
    )  # fmt: skip
    got = listed("action", "info", "/not_an_action")
    # ros2cli exits 0; rostool prints the same lines, then its error line, and exits 1 (its rule)
    c.check("test_info_on_nonexistent_action (exit 1 by rule)", got.returncode == 1 and got.stdout.splitlines()
            == ["Action: /not_an_action", "Action clients: 0", "Action servers: 0"], got)  # fmt: skip
    out = listed("action", "info", "/fibonacci").stdout.splitlines()
    c.check("test_fibonacci_info", out == ["Action: /fibonacci", "Action clients: 0", "Action servers: 1",
            "    /fibonacci_action_server"], out)  # fmt: skip
    out = listed("action", "info", "-t", "/fibonacci").stdout.splitlines()
    c.check(
        "test_fibonacci_info_with_types",
        out[-1] == "    /fibonacci_action_server [test_msgs/action/Fibonacci]",
        out,
    )
    out = listed("action", "info", "-c", "/fibonacci").stdout.splitlines()
    c.check(
        "test_fibonacci_info_count",
        out == ["Action: /fibonacci", "Action clients: 0", "Action servers: 1"],
        out,
    )
    out = listed("action", "list").stdout
    c.check("test_list", out == "/fibonacci\n", out)
    out = listed("action", "list", "-t").stdout
    c.check("test_list_with_types", out == "/fibonacci [test_msgs/action/Fibonacci]\n", out)
    out = listed("action", "list", "-c").stdout
    c.check("test_list_count", out == "1\n", out)
    got = ros2(env, "action", "send_goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 5}")
    lines, expected = got.stdout.splitlines(), fibonacci_send_goal_output(5)
    c.check("test_send_fibonacci_goal", got.returncode == 0 and len(lines) == len(expected)
            and all(matches(e, x) for e, x in zip(expected, lines, strict=False)), got)  # fmt: skip
    got = ros2(env, "action", "send_goal", "-f", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 5}")
    c.check("test_send_fibonacci_goal_with_feedback", got.returncode == 0
            and in_order(fibonacci_send_goal_output(5, with_feedback=1), got.stdout.splitlines()), got)  # fmt: skip
    out = listed("action", "type", "/fibonacci").stdout
    c.check("action type (Kilted)", out == "test_msgs/action/Fibonacci\n", out)
    got = listed("action", "type", "/not_an_action")
    c.check("action type of no action (Kilted)", got.returncode == 1 and got.stdout == "", got)
    out = listed("action", "find", "test_msgs/action/Fibonacci").stdout
    c.check("action find (Kilted)", out == "/fibonacci\n", out)
    out = listed("action", "find", "-c", "test_msgs/action/Fibonacci").stdout
    c.check("action find -c (Kilted)", out == "1\n", out)
    c.done()
