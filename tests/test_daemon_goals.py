"""Goals the graph daemon sends for the verb (goal_server.py, goal_client.py): with a warm daemon,
`action send_goal` (ros2's form, and send-goal) prints exactly what the direct way (its own participant)
prints, with the same exit codes, on both backends: a succeeded goal with --feedback, --json with its type
looked up, an unknown action, a goal its type does not fit, and a --timeout that cancels the goal; the
daemon sent them (its query count); Ctrl+C after the first feedback ends the verb with 130 and the goal
canceled on the server (the real node reports it). Referee: a real rclpy node (Jazzy, Kilted) serving
test_msgs/action/Fibonacci."""

from __future__ import annotations

import re
import time
from collections.abc import Callable

from tests.ros2_backends import Tool, ToolPopen, rostool_lines
from tests.ros2_peers import RclpyPeer
from tests.support import Watched
from tests.test_daemon import graph_env  # noqa: F401 (the fixture: the daemon allowed, its own directory)
from tests.test_daemon_calls import queries
from tests.test_daemon_relay import started_daemon

FIB = "test_msgs/action/Fibonacci"
GOALS = [
    ["action", "send_goal", "/fibonacci", FIB, "{order: 3}", "--feedback"],
    ["action", "send-goal", "/fibonacci", "{order: 2}", "--json"],  # the type from the daemon's graph
    ["action", "send_goal", "/nobody", "{order: 2}"],  # unknown action: one line, exit 1
    ["action", "send_goal", "/fibonacci", FIB, "{nope: 1}"],  # a goal its type does not fit: one line
    # canceled, exit 1: a timeout the direct way's own discovery fits in (1.1-1.7 s), and a goal of 4.5 s
    # (int32 Fibonacci numbers end at the 46th)
    ["action", "send_goal", "/fibonacci", FIB, "{order: 45}", "--timeout", "3"],
]
GOAL_ID = re.compile(r"\b[0-9a-f]{32}\b")
NUMBER_LINE = re.compile(r"^- \d+\n", re.MULTILINE)  # a canceled goal's sequence: as long as it got


def _seen(done: object, timed: bool = False) -> tuple[int, str, list[str]]:
    """Exit code, stdout and rostool's stderr lines, each goal's random id as one placeholder (`timed`: the
    result's numbers left out, as many as the goal had made when it was canceled)."""
    code, out, err = done.returncode, done.stdout, done.stderr  # type: ignore[attr-defined]
    out = GOAL_ID.sub("<id>", NUMBER_LINE.sub("", out) if timed else out)
    return code, out, [GOAL_ID.sub("<id>", line) for line in rostool_lines(err)]


def test_goals_through_the_daemon_print_as_the_direct_way_and_ctrl_c_cancels(
    tool: Tool,
    tool_popen: ToolPopen,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
) -> None:
    peer = start_peer("--name", "fib", "--action", "/fibonacci", "--step", "0.1")
    started_daemon(tool)
    before = queries(tool)
    served_runs = []
    for goal in GOALS:
        served = tool(["--ros2", *goal])
        served_runs.append(served)
        graph_env["ROSTOOL_NO_DAEMON"] = "1"  # the direct way
        direct = tool(["--ros2", *goal])
        graph_env["ROSTOOL_NO_DAEMON"] = ""
        timed = "--timeout" in goal
        assert _seen(served, timed) == _seen(direct, timed), goal
    # each verb's goal was sent by the daemon (a query-counted request of its own)
    assert queries(tool) - before >= len(GOALS)

    # what a served goal printed, to be sure the comparison above compared goals that ran
    first, timed_out = served_runs[0], served_runs[-1]
    assert first.returncode == 0, first.stderr
    assert "Feedback:\n    sequence:\n- 0\n- 1\n- 1\n" in first.stdout, first.stdout
    assert first.stdout.endswith("Goal finished with status: SUCCEEDED\n"), first.stdout
    assert timed_out.returncode == 1 and "Canceling goal...\n" in timed_out.stdout, timed_out.stdout
    assert timed_out.stdout.endswith("Goal finished with status: CANCELED\n"), timed_out.stdout
    assert re.fullmatch(r"rostool: goal [0-9a-f]{32} got no result within 3 s; canceled it",
                        rostool_lines(timed_out.stderr)[-1]), timed_out.stderr  # fmt: skip

    # Ctrl+C after the first feedback: the daemon cancels the goal on the server, the verb ends with 130
    canceled_before = len(peer.of("canceled"))  # the --timeout goals' cancels came before
    watched = Watched(tool_popen(["--ros2", "action", "send_goal", "/fibonacci", FIB, "{order: 45}", "-f"]))
    watched.wait_for(lambda out: "Feedback:" in out, timeout=20)
    began = time.monotonic()
    out, err = watched.stop(timeout=10)
    assert watched.proc.returncode == 130, (out, err)
    assert "Traceback" not in err and "Canceling goal...\n" in out, (out, err)
    assert out.rstrip().endswith("Goal finished with status: CANCELED"), out
    assert time.monotonic() - began < 5.0
    peer.wait_for("cancel", timeout=10)
    peer.wait_for("canceled", lambda _e: len(peer.of("canceled")) > canceled_before, timeout=10)
