"""Subscriptions relayed by the graph daemon, against real rclpy peers on both backends: `topic echo` through
a warm daemon prints the real talker's messages from the daemon's reader (the talker sees the daemon's
node subscribe, never the verb's own), the daemon's reader leaves the talker's view when the verb exits
(also when it is killed with SIGKILL), `--no-daemon` subscribes itself, and two verbs at once each get
their messages. Each test has its own daemon directory (test_daemon.py's `graph_env`)."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

import pytest

from tests.ros2_backends import Tool, ToolPopen
from tests.ros2_peers import RclpyPeer, bound_addresses
from tests.support import Watched, wait_until
from tests.test_daemon import graph_env  # noqa: F401 (the fixture: the daemon allowed, its own directory)

DAEMON_NODE = "/_rostool_daemon_"  # and its pid
# how a Kilted (Fast DDS 3) node may name a Cyclone participant's endpoints (issue 21): the count still holds
BARE = "_CREATED_BY_BARE_DDS_APP_"
MESSAGE = re.compile(r"^data: hello (\d+)$", re.MULTILINE)


def relays(tool: Tool) -> list[str]:
    """The topics the daemon relays now (`daemon status --json`)."""
    done = tool(["daemon", "status", "--json"])
    assert done.returncode == 0, done.stderr
    return list(json.loads(done.stdout).get("relays", ["status without relays"]))


def subscribers(talker: RclpyPeer, topic: str) -> list[str]:
    """The nodes subscribed to `topic` in the talker's own latest view of the graph."""
    views = talker.of("graph")
    return list(views[-1]["subscribers"].get(topic, [])) if views else []


def seen_later(talker: RclpyPeer, check: Callable[[list[str]], bool], timeout: float = 20) -> bool:
    """Whether a view of /t the talker reports from now on satisfies `check`."""
    start = len(talker.of("graph"))
    return wait_until(lambda: len(talker.of("graph")) > start and check(subscribers(talker, "/t")), timeout)


def only(nodes: list[str], name: Callable[[str], bool], count: int) -> bool:
    """`count` subscribers, each `name`d so (or left unnamed by a Kilted node)."""
    return len(nodes) == count and all(name(node) or BARE in node for node in nodes)


def daemons(nodes: list[str]) -> bool:
    """One subscriber: the daemon's reader."""
    return only(nodes, lambda node: node.startswith(DAEMON_NODE), 1)


def numbers(out: str) -> list[int]:
    return [int(n) for n in MESSAGE.findall(out)]


def started_daemon(tool: Tool) -> None:
    done = tool(["daemon", "start"], timeout=60)
    assert done.stdout.strip() == "The daemon has been started", done.stderr


def test_echo_through_the_daemon_and_its_reader_leaves_with_the_verb(
    tool: Tool, tool_popen: ToolPopen, start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]  # noqa: F811
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/t", "--rate", "20", "--watch")
    started_daemon(tool)
    once = tool(["topic", "echo", "/t", "--once"])
    assert once.returncode == 0 and once.stderr_lines == [], once.stderr  # type: ignore[attr-defined]
    published = talker.of("published")
    assert len(numbers(once.stdout)) == 1 and (not published or numbers(once.stdout)[0] >= 1)
    assert once.stdout.rstrip().endswith("---")
    assert wait_until(lambda: relays(tool) == [], timeout=10)  # the --once verb's relay closed with it

    # a running echo: the talker sees the daemon's node subscribe to /t, not the verb's own node
    echo = Watched(tool_popen(["topic", "echo", "/t"]))
    try:
        assert echo.wait_for(lambda out: len(numbers(out)) >= 3), echo.stop()
        got = numbers(echo.stdout)
        assert got == list(range(got[0], got[0] + len(got)))  # consecutive: nothing lost or reordered
        assert relays(tool) == ["/t"]
        assert seen_later(talker, daemons), subscribers(talker, "/t")
        assert bound_addresses(echo.proc.pid) == []  # the verb never joined the graph: no UDP socket
        echo.proc.kill()  # SIGKILL: no goodbye; the daemon sees its connection end
        echo.proc.wait(timeout=10)
    finally:
        echo.stop()
    assert wait_until(lambda: relays(tool) == [], timeout=10)
    assert seen_later(talker, lambda nodes: nodes == []), subscribers(talker, "/t")


def test_no_daemon_echo_subscribes_itself(
    tool: Tool, tool_popen: ToolPopen, start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]  # noqa: F811
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/t", "--rate", "20", "--watch")
    started_daemon(tool)
    echo = Watched(tool_popen(["topic", "echo", "/t", "--no-daemon"]))
    try:
        assert echo.wait_for(lambda out: len(numbers(out)) >= 2), echo.stop()
        own = f"/rostool_{echo.proc.pid}"
        assert seen_later(talker, lambda nodes: only(nodes, own.__eq__, 1)), (own, subscribers(talker, "/t"))
        assert bound_addresses(echo.proc.pid) != []  # its own participant
        assert relays(tool) == []
    finally:
        echo.stop()


def test_two_verbs_at_once_each_get_their_messages(
    tool: Tool, tool_popen: ToolPopen, start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]  # noqa: F811
) -> None:
    start_peer("--name", "talker", "--talk", "/t", "--rate", "20")
    start_peer("--name", "other", "--talk", "/u", "--rate", "20")
    started_daemon(tool)
    first = Watched(tool_popen(["topic", "echo", "/t", "-n", "5"]))
    second = Watched(tool_popen(["topic", "echo", "/u", "-n", "5", "--qos-reliability", "best_effort"]))
    outs: list[Any] = []
    for echo in (first, second):
        assert echo.proc.wait(timeout=30) == 0
        outs.append(echo.stop())
    for out, err in outs:
        got = numbers(out)
        assert len(got) == 5 and got == list(range(got[0], got[0] + 5)), (out, err)
    assert wait_until(lambda: relays(tool) == [], timeout=10)


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_relay_outlives_its_daemon(
    tool: Tool, tool_popen: ToolPopen, start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]  # noqa: F811
) -> None:
    start_peer("--name", "talker", "--talk", "/t", "--rate", "20")
    started_daemon(tool)
    echo = Watched(tool_popen(["topic", "echo", "/t"]))
    try:
        assert echo.wait_for(lambda out: len(numbers(out)) >= 2), echo.stop()
        assert tool(["daemon", "stop"]).returncode == 0
        before = len(numbers(echo.stdout))
        # the verb subscribes itself and goes on: more messages, one warning line
        assert echo.wait_for(lambda out: len(numbers(out)) >= before + 5, timeout=30), echo.stop()
    finally:
        _out, err = echo.stop()
    warnings = [line for line in err.splitlines() if "graph daemon stopped relaying /t" in line]
    assert len(warnings) == 1, err
