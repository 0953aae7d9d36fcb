"""Parameters and service calls made by the graph daemon for the verb (issue 37 item 5): with a warm daemon,
`param list/get/set/describe`, `service call` (type given, and type looked up) and their errors print
exactly what the direct way (`--no-daemon`, its own participant) prints, with the same exit codes, on
both backends; the daemon answered them (its query count), and the real rclpy node's parameter changed
(read back by the peer itself). Referee: a real rclpy node (Jazzy, Kilted) with parameters of every type
and a std_srvs/srv/SetBool server."""

from __future__ import annotations

from collections.abc import Callable

from tests.ros2_backends import Tool, rostool_lines
from tests.ros2_peers import RclpyPeer
from tests.test_daemon import graph_env  # noqa: F401 (the fixture: the daemon allowed, its own directory)
from tests.test_daemon_relay import started_daemon

CALLS = [
    ["param", "list", "/node"],
    ["param", "get", "/node", "ids"],
    ["param", "describe", "/node", "speed"],
    ["param", "get", "/node", "missing"],
    ["param", "get", "/nobody", "x"],
    ["service", "call", "/sb", "std_srvs/srv/SetBool", "{data: true}"],
    ["service", "call", "/sb", "{data: false}"],
]


def queries(tool: Tool) -> int:
    import json

    done = tool(["daemon", "status", "--json"])
    assert done.returncode == 0, done.stderr
    return int(json.loads(done.stdout)["queries"])


def test_calls_through_the_daemon_answer_as_the_direct_way(
    tool: Tool,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
) -> None:
    peer = start_peer("--name", "node", "--params", "--service", "/sb")
    started_daemon(tool)
    before = queries(tool)
    for call in CALLS:
        served = tool(["--ros2", *call])
        graph_env["ROSTOOL_NO_DAEMON"] = "1"  # the direct way (`service call` has no --no-daemon)
        direct = tool(["--ros2", *call])
        graph_env["ROSTOOL_NO_DAEMON"] = ""
        assert (served.returncode, served.stdout, rostool_lines(served.stderr)) == (
            direct.returncode, direct.stdout, rostool_lines(direct.stderr)
        ), call  # fmt: skip
    assert queries(tool) - before >= 2 * len(CALLS)  # each verb asked the daemon (several asks each)

    # a set through the daemon reaches the real node: it reports the change itself
    done = tool(["--ros2", "param", "set", "/node", "count", "42"])
    assert (done.returncode, done.stdout) == (0, "Set parameter successful\n"), done.stderr
    peer.wait_for("param", lambda e: e["name"] == "count" and e["value"] == 42, timeout=10)
    done = tool(["--ros2", "param", "get", "/node", "count"])
    assert done.stdout == "Integer value is: 42\n", done.stderr
