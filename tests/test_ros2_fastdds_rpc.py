"""Services, parameters and actions against real rclpy nodes (Jazzy and Kilted, rmw_fastrtps_cpp), on both
ROS 2 backends: rostool's DDS and rclpy (tests/ros2_backends.py).

Fast DDS pairs a reply with its request by RTPS sample identity, not by an in-payload header as
rmw_cyclonedds_cpp does; rostool picks the convention by the server's GUID vendor (services.py). Every test
asserts both sides: what rostool printed and what the real node's callback saw (tests/rclpy_peer.py's
events). One-shot CLI calls are repeated because each one is a fresh participant racing discovery, where
lost replies used to show (Cyclone drops what a Fast DDS writer's first heartbeat announces).
"""

from __future__ import annotations

import json
import signal
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from tests.ros2_peers import RclpyPeer
from tests.support import stop

if TYPE_CHECKING:
    from tests.ros2_backends import Tool, ToolPopen

Start = Callable[..., RclpyPeer]
pytest_plugins = ("tests.ros2_backends",)  # the `tool`, `tool_popen` and `backend` fixtures
CALLS = 3  # fresh rostool processes per check
T = TypeVar("T")


def test_service_call_reaches_the_real_server(start_peer: Start, tool: Tool) -> None:
    peer = start_peer("--name", "flags", "--service", "/set_flag")
    for attempt in range(CALLS):
        called = tool(["service", "call", "/set_flag", "std_srvs/srv/SetBool", "{data: true}"])
        assert called.returncode == 0, called.stderr
        assert "requester: making request: std_srvs.srv.SetBool_Request(data=True)" in called.stdout
        assert "std_srvs.srv.SetBool_Response(success=True, message='flag is True')" in called.stdout
        assert len(peer.of("service")) == attempt + 1
    assert all(event["data"] is True for event in peer.of("service"))
    # the type from discovery, JSON out, data false
    called = tool(["service", "call", "/set_flag", "{data: false}", "--json"])
    assert called.returncode == 0, called.stderr
    assert json.loads(called.stdout) == {"success": False, "message": "flag is False"}
    peer.wait_for("service", lambda e: e["data"] is False)
    assert len(peer.of("service")) == CALLS + 1  # never a request twice, never a corrupt one


def test_service_type_list_and_find(start_peer: Start, tool: Tool) -> None:
    start_peer("--name", "flags", "--service", "/set_flag")
    reads = [(None, ["service", "type", "/set_flag"]), (None, ["service", "list", "-t"])]
    typed, listing = in_lanes(tool, reads)  # side by side: both only list
    assert typed.stdout == "std_srvs/srv/SetBool\n"
    listed = listing.stdout.splitlines()
    assert "/set_flag [std_srvs/srv/SetBool]" in listed
    assert "/flags/list_parameters [rcl_interfaces/srv/ListParameters]" in listed


def test_service_call_without_a_server_ends_in_one_line(start_peer: Start, tool: Tool) -> None:
    start_peer("--name", "flags", "--service", "/set_flag")
    called = tool(["service", "call", "/nothing", "std_srvs/srv/SetBool", "{data: true}", "--timeout", "2"])
    assert called.returncode != 0
    assert called.stdout == ""
    lines = called.stderr_lines
    assert len(lines) == 1 and "/nothing" in lines[0], called.stderr


def in_lanes(
    run: Callable[[list[str]], T], calls: Sequence[tuple[str | None, list[str]]], workers: int = 4
) -> list[T]:
    """run(args) of each (lane, args), side by side (`workers` at a time: more fresh participants at once
    only make each one's discovery slower on two cores); the runs of one lane (not None) one after the other.
    A lane is a service: rostool's DDS client of a Fast DDS server takes the first reply after its request,
    which may be another client's if two call the server at once (rostool/graph/ros2/services.py)."""
    lanes: dict[object, list[int]] = {}
    for index, (lane, _args) in enumerate(calls):
        lanes.setdefault(index if lane is None else lane, []).append(index)
    results: dict[int, T] = {}

    def run_lane(indexes: list[int]) -> None:
        for index in indexes:
            results[index] = run(calls[index][1])

    with ThreadPoolExecutor(max_workers=min(workers, len(lanes))) as pool:
        for done in [pool.submit(run_lane, indexes) for indexes in lanes.values()]:
            done.result()
    return [results[index] for index in range(len(calls))]


def test_parameters_of_a_real_node(start_peer: Start, tool: Tool, tmp_path: Path, backend: str) -> None:
    """Each change in order; the runs that only read (or change another parameter) side by side, on the
    DDS backend one at a time per parameter service (see in_lanes)."""

    def lane(service: str) -> str | None:
        return service if backend == "dds" else None

    peer = start_peer("--name", "talker", "--params")
    names, speed, ids, described = in_lanes(tool, [
        (lane("list"), ["param", "list", "/talker"]), (lane("get"), ["param", "get", "/talker", "speed"]),
        (lane("get"), ["param", "get", "/talker", "ids"]),
        (lane("describe"), ["param", "describe", "/talker", "label"]),
    ])  # fmt: skip
    assert names.returncode == 0, names.stderr
    listed = names.stdout.split()
    assert {"flag", "count", "speed", "label", "blob", "ids", "gains", "names", "use_sim_time"} <= set(listed)
    assert speed.stdout == "Double value is: 0.5\n"
    assert ids.stdout == "Integer values are: [1, 2, 3]\n"
    assert "Parameter name: label" in described.stdout and "Type: string" in described.stdout

    changed = tool(["param", "set", "/talker", "speed", "0.75"])
    assert changed.stdout == "Set parameter successful\n", changed.stderr
    peer.wait_for("param", lambda e: e["name"] == "speed" and e["value"] == 0.75)  # the node's own view
    speed, dumped = in_lanes(tool, [(lane("get"), ["param", "get", "/talker", "speed"]),
                                    (lane("get"), ["param", "dump", "/talker"])])  # fmt: skip
    assert speed.stdout == "Double value is: 0.75\n"
    assert dumped.returncode == 0, dumped.stderr
    assert "    speed: 0.75\n" in dumped.stdout and "    label: r2\n" in dumped.stdout

    params_file = tmp_path / "talker.yaml"
    params_file.write_text("/talker:\n  ros__parameters:\n    label: r3\n    count: 7\n")
    # rclpy refuses to undeclare a declared parameter: rostool reports the node's reason (speed, which the
    # load does not touch)
    loaded, deleted = in_lanes(tool, [(lane("set"), ["param", "load", "/talker", str(params_file)]),
                                      (lane("set"), ["param", "delete", "/talker", "speed"])])  # fmt: skip
    assert loaded.returncode == 0, loaded.stderr
    peer.wait_for("param", lambda e: e["name"] == "label" and e["value"] == "r3")
    peer.wait_for("param", lambda e: e["name"] == "count" and e["value"] == 7)
    assert deleted.returncode != 0
    (line,) = deleted.stderr_lines
    assert line.startswith("rostool: Deleting parameter failed: Static parameter cannot be undeclared"), line


def test_action_goal_with_feedback_and_result(start_peer: Start, tool: Tool) -> None:
    peer = start_peer("--name", "fib", "--action", "/fibonacci", "--step", "0.05")
    for attempt in range(2):
        sent = tool(
            ["action", "send-goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 5}", "--feedback",
             "--json"]
        )  # fmt: skip
        assert sent.returncode == 0, sent.stderr
        events = [json.loads(line) for line in sent.stdout.splitlines()]
        assert events[0]["event"] == "sent" and events[0]["accepted"] is True
        feedback = [e["feedback"]["sequence"] for e in events if e["event"] == "feedback"]
        # every feedback, the first one too (a second goal meets a writer with history)
        assert feedback == [[0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3], [0, 1, 1, 2, 3, 5]], attempt
        result = {"event": "result", "status": "SUCCEEDED", "result": {"sequence": [0, 1, 1, 2, 3, 5]}}
        assert events[-1] == result
        assert len(peer.of("done")) == attempt + 1
    assert peer.of("done")[-1]["sequence"] == [0, 1, 1, 2, 3, 5]
    assert [e["order"] for e in peer.of("goal")] == [5, 5]


def test_action_timeout_cancels_the_goal_on_the_server(start_peer: Start, tool: Tool) -> None:
    """The timeout counts from the start, discovery included (a new Fast DDS participant may wait up to 3 s
    for the server's next announcement, more on a loaded machine), and the goal takes 12 s."""
    peer = start_peer("--name", "fib", "--action", "/fibonacci", "--step", "0.3")
    sent = tool(
        ["action", "send-goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 40}", "--timeout", "8"]
    )
    assert sent.returncode != 0
    assert "Goal finished with status: CANCELED" in sent.stdout
    assert "canceled it" in sent.stderr
    peer.wait_for("cancel")
    peer.wait_for("canceled")
    assert not peer.of("done")


def test_action_ctrl_c_cancels_the_goal_on_the_server(start_peer: Start, tool_popen: ToolPopen) -> None:
    peer = start_peer("--name", "fib", "--action", "/fibonacci", "--step", "0.3")
    proc = tool_popen(["action", "send-goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 30}"])
    try:
        peer.wait_for("goal", timeout=20)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
    finally:
        stop(proc)
    assert proc.returncode == 130, err
    # the server runs the goal before rostool hears that it was accepted: Ctrl+C in between cancels too
    assert "Canceling goal..." in out, err
    peer.wait_for("cancel")
    peer.wait_for("canceled")
    assert not peer.of("done")


def test_action_cancel_verb_reaches_the_server(start_peer: Start, tool: Tool, tool_popen: ToolPopen) -> None:
    peer = start_peer("--name", "fib", "--action", "/fibonacci", "--step", "0.3")
    goal = ["action", "send-goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 30}", "--json"]
    proc = tool_popen(goal)
    try:
        peer.wait_for("goal", timeout=20)
        canceled = tool(["action", "cancel", "/fibonacci"])
        out, err = proc.communicate(timeout=20)
    finally:
        stop(proc)
    assert canceled.returncode == 0, canceled.stderr
    goal_id = json.loads(out.splitlines()[0])["goal_id"]
    assert canceled.stdout.split() == ["Canceling", "1", "goal(s)", "of", "/fibonacci:", goal_id]
    peer.wait_for("cancel")
    assert json.loads(out.splitlines()[-1])["status"] == "CANCELED", err


def test_action_list_and_info_name_the_real_server(start_peer: Start, tool: Tool) -> None:
    start_peer("--name", "fib", "--action", "/fibonacci")
    reads = [(None, ["action", "list", "-t"]), (None, ["action", "info", "/fibonacci"])]
    listed, described = in_lanes(tool, reads)  # side by side: both only list
    assert listed.stdout.splitlines() == ["/fibonacci [test_msgs/action/Fibonacci]"], listed.stderr
    info = described.stdout.splitlines()
    assert info[0] == "Action: /fibonacci"
    assert info[info.index("Action servers: 1") + 1] == "    /fib"  # the node, once it has named itself
    assert "Action clients: 0" in info
