"""Bad input to the live-graph verbs: one clear line on stderr, a non-zero exit, never a traceback."""

from __future__ import annotations

import subprocess

import pytest

from tests.support import free_port, rostool, rostool_popen, stop, wait_until


def assert_one_line_error(result: subprocess.CompletedProcess[str], *fragments: str) -> None:
    assert result.returncode != 0
    assert "Traceback" not in result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_master_unreachable_says_where_and_suggests_core(ros_env: dict[str, str]) -> None:
    env = {**ros_env, "ROS_MASTER_URI": f"http://127.0.0.1:{free_port()}"}
    for args in (["topic", "list"], ["node", "list"], ["param", "get", "/x"], ["topic", "echo", "/x"]):
        result = rostool(args, env)
        assert_one_line_error(result, env["ROS_MASTER_URI"], "rostool core")


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["topic", "info", "/nope"], ["unknown topic /nope"]),
        (["topic", "type", "/nope"], ["unknown topic /nope"]),
        (["node", "info", "/nope"], ["unknown node /nope"]),
        (["node", "kill", "/nope"], ["unknown node /nope"]),
        (["param", "get", "/nope"], ["/nope is not set"]),
        (["param", "delete", "/nope"], ["/nope"]),
        (["param", "set", "/x", "{a: [1"], ["invalid YAML"]),
        (["topic", "pub", "/t", "std_msgs/Strin", "x", "-1"], ["unknown message type std_msgs/Strin"]),
        (["topic", "pub", "/t", "std_msgs/String", "{dta: x}", "-1"], ["no field 'dta'", "data"]),
        (["topic", "pub", "/t", "std_msgs/Int32", "data: hello", "-1"], ["'data' is an int32", "hello"]),
        (["topic", "pub", "/t", "std_msgs/UInt8", "300", "-1"], ["out of range"]),
        (["topic", "pub", "/t", "geometry_msgs/Point", "1", "2", "3", "4", "-1"], ["takes 3 value(s)"]),
        (["topic", "pub", "/t", "std_msgs/String", "data: [unclosed", "-1"], ["invalid YAML"]),
        (["topic", "echo", "/t", "--filter", "__import__('os')"], ["not allowed"]),
        (["msg", "show", "nope_msgs/Nothing"], ["unknown message type"]),
    ],
)
def test_bad_input(rostool_master: dict[str, str], args: list[str], fragments: list[str]) -> None:
    assert_one_line_error(rostool(args, rostool_master, timeout=20), *fragments)


def test_publishing_a_different_type_on_a_known_topic_is_refused(rostool_master: dict[str, str]) -> None:
    env = rostool_master
    first = rostool_popen(["topic", "pub", "/typed", "std_msgs/String", "data: a"], env)
    try:
        assert wait_until(lambda: rostool(["topic", "type", "/typed"], env).stdout == "std_msgs/String\n")
        result = rostool(["topic", "pub", "/typed", "std_msgs/Int32", "1", "-1"], env)
        assert_one_line_error(result, "/typed already has type std_msgs/String")
    finally:
        stop(first)


def test_ctrl_c_while_waiting_is_quiet(rostool_master: dict[str, str]) -> None:
    for args in (["topic", "echo", "/quiet"], ["topic", "hz", "/quiet"], ["node", "ping", "/nobody"]):
        proc = rostool_popen(args, rostool_master)
        wait_until(lambda: False, 1.0)
        _out, err = stop(proc)
        assert "Traceback" not in err and "Aborted" not in err
        assert proc.returncode in (130, 1)  # ping of an unknown node fails before the interrupt
