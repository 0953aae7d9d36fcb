"""Subscriptions relayed by the graph daemon, against real rclpy peers on both backends: `topic echo` through
a warm daemon prints the real talker's messages from the daemon's reader (the talker sees the daemon's
node subscribe, never the verb's own), the daemon's reader leaves the talker's view when the verb exits
(also when it is killed with SIGKILL), `--no-daemon` subscribes itself, and two verbs at once each get
their messages. Each test has its own daemon directory (test_daemon.py's `graph_env`)."""

from __future__ import annotations

import json
import re
import socket
import struct
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.ros2_backends import Tool, ToolPopen, rostool_lines
from tests.ros2_peers import RclpyPeer, bound_addresses
from tests.support import TESTDATA, Watched, interface_workspace, rostool, rostool_popen, stop, wait_until
from tests.test_daemon import graph_env  # noqa: F401 (the fixture: the daemon allowed, its own directory)
from tests.test_ros2_interfaces import SOURCES
from tests.test_ros2_type_description import EXPECTED_STATUS, STATUS

ROS2_BAGS = TESTDATA / "ros2"
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
    tool: Tool,
    tool_popen: ToolPopen,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
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
        assert "  relays: 1 (/t)\n" in tool(["daemon", "status"]).stdout  # the text form says it too
        assert seen_later(talker, daemons), subscribers(talker, "/t")
        assert bound_addresses(echo.proc.pid) == []  # the verb never joined the graph: no UDP socket
        echo.proc.kill()  # SIGKILL: no goodbye; the daemon sees its connection end
        echo.proc.wait(timeout=10)
    finally:
        echo.stop()
    assert wait_until(lambda: relays(tool) == [], timeout=10)
    assert seen_later(talker, lambda nodes: nodes == []), subscribers(talker, "/t")


def test_no_daemon_echo_subscribes_itself(
    tool: Tool,
    tool_popen: ToolPopen,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
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
    tool: Tool,
    tool_popen: ToolPopen,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
) -> None:
    start_peer("--name", "talker", "--talk", "/t", "--rate", "20")
    start_peer("--name", "other", "--talk", "/u", "--rate", "20")
    started_daemon(tool)
    first = Watched(tool_popen(["topic", "echo", "/t", "-n", "5"]))
    second = Watched(tool_popen(["topic", "echo", "/u", "-n", "5", "--qos-reliability", "best_effort"]))
    third = Watched(tool_popen(["topic", "echo", "/t"]))  # ended with Ctrl+C
    outs: list[Any] = []
    for echo in (first, second):
        assert echo.proc.wait(timeout=30) == 0
        outs.append(echo.stop())
    for out, err in outs:
        got = numbers(out)
        assert len(got) == 5 and got == list(range(got[0], got[0] + 5)), (out, err)
    assert third.wait_for(lambda out: len(numbers(out)) >= 5), third.stop()
    _out, err = third.stop()
    assert third.proc.returncode == 130 and rostool_lines(err) == [], err
    assert wait_until(lambda: relays(tool) == [], timeout=10)


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_relay_outlives_its_daemon(
    tool: Tool,
    tool_popen: ToolPopen,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
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


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_qos_no_publisher_serves_fails_as_directly(
    tool: Tool,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
) -> None:
    start_peer("--name", "talker", "--talk", "/t", "--rate", "20", "--best-effort")
    started_daemon(tool)
    args = ["topic", "echo", "/t", "--once", "--qos-reliability", "reliable", "--timeout", "20"]
    served, direct = tool(args), tool([*args, "--no-daemon"])
    for done in (served, direct):
        lines = done.stderr_lines  # type: ignore[attr-defined]
        assert done.returncode == 1 and len(lines) == 1 and done.stdout == "", done.stderr
        assert "incompatible policy" in lines[0] and "adjust --qos-reliability" in lines[0]
    assert served.stderr_lines == direct.stderr_lines  # type: ignore[attr-defined]


def test_a_type_only_the_publisher_knows_comes_with_the_relay(
    graph_env: dict[str, str],  # noqa: F811
    tmp_path: Path,
) -> None:
    sources = interface_workspace(tmp_path / "ws", SOURCES)
    args = ["topic", "pub", "/status", "robo_msgs/msg/Status", STATUS, "-r", "10", "--interfaces"]
    publisher = rostool_popen([*args, str(sources)], {**graph_env, "ROSTOOL_NO_DAEMON": "1"})
    try:
        done = rostool(["daemon", "start"], graph_env, timeout=60)
        assert done.returncode == 0, done.stderr
        # neither this process (no sources) nor the DDS daemon knows the type: the daemon learns it from
        # the publisher's node, this process from the daemon's relay
        echoed = rostool(["topic", "echo", "/status", "-n", "2", "--json"], graph_env, cwd=tmp_path)
        assert echoed.returncode == 0 and echoed.stderr == "", echoed.stderr
        assert [json.loads(line) for line in echoed.stdout.splitlines()] == [EXPECTED_STATUS] * 2
        yaml = rostool(["topic", "echo", "/status", "-n", "1", "--field", "parts"], graph_env, cwd=tmp_path)
        assert "label: leg" in yaml.stdout and "weight: 0.5" in yaml.stdout, yaml.stderr
        status = json.loads(rostool(["daemon", "status", "--json"], graph_env).stdout)
        assert Path(status["log"]).read_text().count("relaying /status") == 2
    finally:
        stop(publisher)


@pytest.mark.parametrize("distro", ["jazzy"])
def test_bag_play_through_a_serving_daemon_publishes_the_bags_types(
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
) -> None:
    # the verb's types are made before its direct graph (which only publishing needs): what play
    # registers in them must reach the graph that publishes
    listener = start_peer("--name", "listener", "--listen", "/talk")
    assert rostool(["daemon", "start"], graph_env, timeout=60).returncode == 0
    play = ["--ros2", "bag", "play", str(ROS2_BAGS / "talker_mcap"), "--topics", "/topic",
            "--remap", "/topic:=/talk", "-r", "2", "-d", "1"]  # fmt: skip
    played = rostool(play, graph_env, timeout=60)
    assert played.returncode == 0, played.stderr
    assert wait_until(lambda: len(listener.of("heard")) >= 10, timeout=10)
    assert [e["data"] for e in listener.of("heard")] == [f"Hello, world! {i}" for i in range(10)]


def test_relay_frames_carry_bytes_and_times_and_refuse_what_is_over_the_limit() -> None:
    from rostool.graph.daemon import wire

    left, right = socket.socketpair()
    with left, right, right.makefile("rb") as stream:
        big = bytes(range(256)) * 4096  # 1 MiB: sent after its header
        frames = [(wire.TYPE, 0, b'{"name": "x"}'), (wire.MESSAGE, 123, b"\x00\x01"), (wire.MESSAGE, 7, big),
                  (wire.WARNING, 9, b"a line")]  # fmt: skip
        sender = threading.Thread(target=wire.send_frames, args=(left, frames))
        sender.start()
        assert [wire.receive_frame(stream) for _ in frames] == frames
        sender.join()
        left.sendall(struct.pack(">IcQ", wire.MAX_SAMPLE + 1, wire.MESSAGE, 1))  # a header that lies
        with pytest.raises(wire.WireError, match="over the"):
            wire.receive_frame(stream)
        left.sendall(struct.pack(">IcQ", 10, wire.MESSAGE, 1) + b"short")
        left.close()
        with pytest.raises(wire.WireError, match="closed"):
            wire.receive_frame(stream)
