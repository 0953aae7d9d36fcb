"""console echo/list/get/set against real nodes logging at every level: an rclpy node with its logger
services (tests/console_peer.py) on both ROS 2 backends, and a rospy node under Debian's roscore. A level
set through rostool really changes what the node logs (its debug lines appear on the log topic)."""

from __future__ import annotations

import json
import os
import pty
import re
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from tests import ros2_peers
from tests.ros2_backends import Tool, ToolPopen
from tests.support import (
    debian_popen,
    master_has_node,
    rostool,
    rostool_popen,
    side_by_side,
    stop,
    wait_until,
)

StartScript = Callable[..., Any]
HERE = Path(__file__).resolve().parent


@pytest.fixture
def start_script(monkeypatch: pytest.MonkeyPatch, start_peer: Callable[..., Any]) -> StartScript:
    """start_script("console_peer.py", *args): start_peer's real rclpy node (same venv, loopback-only
    environment, JSON events, teardown checks), running another peer script of tests/."""

    def start(script: str, *args: str) -> Any:
        monkeypatch.setattr(ros2_peers, "PEER_SCRIPT", HERE / script)
        return start_peer(*args)

    return start


LINE = re.compile(r"^\[(DEBUG|INFO|WARN|ERROR|FATAL)\] \[\d+\.\d{9}\] \[([^\]]+)\]: (\w+) (\d+)$")


def read_entries(proc: subprocess.Popen[str], until: str, limit: float = 20) -> list[dict[str, object]]:
    """`console echo --json` entries until one whose msg starts with `until`; the process is stopped."""
    assert proc.stdout is not None
    entries: list[dict[str, object]] = []
    deadline = time.monotonic() + limit
    try:
        for line in proc.stdout:
            entries.append(json.loads(line))
            if str(entries[-1]["msg"]).startswith(until) or time.monotonic() > deadline:
                break
    finally:
        stop(proc)
    return entries


def test_ros2_echo_filters_and_set_changes_the_level(
    tool: Tool,
    tool_popen: ToolPopen,
    start_script: StartScript,
) -> None:
    start_script("console_peer.py")
    # the reads before the level changes side by side; list and get, which both call the node's logger
    # services, one after the other (a DDS client of a Fast DDS server takes the first reply after its
    # request, which may be another client's: see in_lanes in test_ros2_fastdds_rpc.py)
    warned, (listed, level), history = side_by_side([
        lambda: tool(["console", "echo", "--level", "warn", "--node", "/talker", "-n", "6"]),
        lambda: (tool(["console", "list", "/talker"]), tool(["console", "get", "/talker"])),
        lambda: tool(["console", "echo", "--json", "-n", "20"]),  # the node's recent lines (transient local)
    ])  # fmt: skip
    assert warned.returncode == 0, warned.stderr
    lines = [LINE.match(line) for line in warned.stdout.splitlines()]
    assert len(lines) == 6 and all(lines), warned.stdout
    assert {m.group(1) for m in lines if m} <= {"WARN", "ERROR"}
    assert {m.group(2) for m in lines if m} == {"talker"}
    assert all(m.group(1).lower() == m.group(3) for m in lines if m)  # level and text agree

    assert listed.stdout == "talker\n"
    assert level.stdout == "unset\n"
    assert "DEBUG" not in {e["level"] for e in map(json.loads, history.stdout.splitlines())}

    done = tool(["console", "set", "/talker", "debug"])
    assert (done.returncode, done.stdout) == (0, ""), done.stderr
    # after the change: the level read back, beside the echo that waits for a debug line
    echo = tool_popen(["console", "echo", "--json", "--node", "talker"])
    assert tool(["console", "get", "/talker", "talker"]).stdout == "debug\n"
    entries = read_entries(echo, until="debug")
    assert entries[-1]["level"] == "DEBUG" and entries[-1]["name"] == "talker", entries[-5:]
    assert entries[-1]["function"] == "tick" and str(entries[-1]["file"]).endswith("console_peer.py")


def test_ros2_node_without_logger_services_is_one_line(tool: Tool, start_script: StartScript) -> None:
    start_script("console_peer.py", "--no-logger-service")
    asked = (["get", "/talker"], ["set", "/talker", "debug"], ["list", "/talker"], ["get", "/nobody"])
    *refused, unknown = side_by_side([lambda a=args: tool(["console", *a]) for args in asked], workers=4)
    for done in refused:
        assert done.returncode == 1
        assert done.stderr_lines == [  # type: ignore[attr-defined]
            "rostool: node /talker offers no logger services (/talker/get_logger_levels): a ROS 2 node "
            "serves them when created with enable_logger_service=True"
        ]
    assert unknown.stderr_lines == [  # type: ignore[attr-defined]
        "rostool: unknown node /nobody (see `rostool node list`)"
    ]


@pytest.mark.parametrize("distro", ["jazzy"])
def test_echo_colours_levels_only_on_a_terminal(graph_env: dict[str, str], start_script: StartScript) -> None:
    start_script("console_peer.py")
    piped = rostool(["console", "echo", "-n", "4"], graph_env)
    assert "\x1b[" not in piped.stdout and len(piped.stdout.splitlines()) == 4
    leader, follower = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "rostool", "console", "echo", "-n", "4"], env=graph_env, stdout=follower
    )
    os.close(follower)
    out = b""
    while out.count(b"\n") < 4:
        try:
            chunk = os.read(leader, 4096)
        except OSError:
            break
        if not chunk:
            break
        out += chunk
    proc.wait(timeout=30)
    os.close(leader)
    assert b"\x1b[93m[WARN]\x1b[0m" in out or b"\x1b[91m[ERROR]\x1b[0m" in out, out


ROSPY_TALKER = """
import os, sys
sys.stdout = sys.stderr = open(os.devnull, "w")  # its console copy of every line: nobody reads it
import rospy
rospy.init_node('talker')
rate = rospy.Rate(5)
i = 0
while not rospy.is_shutdown():
    i += 1
    rospy.logdebug("debug %d", i)
    rospy.loginfo("info %d", i)
    rospy.logwarn("warn %d", i)
    rospy.logerr("error %d", i)
    rate.sleep()
"""


@pytest.fixture
def rospy_talker(book_master: dict[str, str]) -> Iterator[dict[str, str]]:
    """A rospy node logging at every level, under Debian's roscore (its rosout node gathers the lines on
    /rosout_agg) or under `rostool core` (no rosout node: echo reads /rosout)."""
    proc = debian_popen(["python3", "-c", ROSPY_TALKER], book_master)
    yield book_master
    stop(proc)


def test_ros1_echo_list_get_set_on_a_rospy_node(rospy_talker: dict[str, str]) -> None:
    env = rospy_talker
    assert wait_until(lambda: master_has_node(env["ROS_MASTER_URI"], "/talker"), 20)
    # the reads before the level changes, side by side
    warned, listing, level, topics_level = side_by_side([
        lambda: rostool(["console", "echo", "--level", "warn", "--node", "talker", "-n", "4"], env),
        lambda: rostool(["console", "list", "/talker"], env),
        lambda: rostool(["console", "get", "/talker"], env),
        lambda: rostool(["console", "get", "/talker", "rospy.topics"], env),
    ], workers=4)  # fmt: skip
    lines = [LINE.match(line) for line in warned.stdout.splitlines()]
    assert len(lines) == 4 and all(lines), (warned.stdout, warned.stderr)
    assert {m.group(1) for m in lines if m} <= {"WARN", "ERROR"} and {m.group(2) for m in lines if m} == {
        "/talker"
    }

    listed = listing.stdout.splitlines()
    assert {"rosout", "rospy.topics"} <= set(listed)
    assert level.stdout == "info\n"
    assert topics_level.returncode == 0
    done = rostool(["console", "set", "/talker", "rosout", "DEBUG"], env)
    assert (done.returncode, done.stdout) == (0, ""), done.stderr
    # after the change: the level read back, beside the echo that waits for a debug line
    echo = rostool_popen(["console", "echo", "--json"], env)
    assert rostool(["console", "get", "/talker", "rosout"], env).stdout == "debug\n"
    entries = read_entries(echo, until="debug")
    assert entries[-1]["level"] == "DEBUG" and entries[-1]["name"] == "/talker"
    missing = rostool(["console", "set", "/talker", "no.such.logger", "warn"], env)
    assert missing.returncode == 1 and missing.stderr.startswith(
        "rostool: node /talker has no logger no.such"
    )
