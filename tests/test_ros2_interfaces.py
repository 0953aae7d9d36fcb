"""ROS 2 custom interfaces from a source tree (no build): a .msg, .srv and .action of a package `robo_msgs`
that no type store knows, used by a ROS 2 node built on rostool's library (ROBO_NODE below) and by rostool
processes given `--interfaces` (or ROSTOOL_INTERFACES). Also `service info` and `action cancel` on ROS 2."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import interface_workspace, rostool, rostool_popen, stop
from tests.test_ros2_graph import ros2_env

SOURCES = {
    "robo_msgs/msg/Part.msg": "# one part of a robot\nstring label\nfloat64 weight 0.5  # kg (a default)\n",
    "robo_msgs/msg/Status.msg": "int32 LEVEL_MAX=9\nstring name 'un#named'\nPart[] parts\n"
    "geometry_msgs/Point where\n",
    "robo_msgs/srv/Rate.srv": "Status status\nint64 factor\n---\nint64 score\nstring summary\n",
    "robo_msgs/action/Count.action": "int32 count 2\nstring label\n---\nint32[] done\n---\n"
    "int32 step\nPart part\n",
}

# Serves robo_msgs/srv/Rate on /rate and robo_msgs/action/Count on /count; argv: sources, seconds per step.
# The cancel service takes a zero goal id as "every active goal", as rcl_action does.
ROBO_NODE = r"""
import sys, threading, time
from cyclonedds._clayer import ddspy_write
from rostool.graph.ros2.actions import FEEDBACK_QOS
from rostool.interfaces.ros2_action import register_action
from rostool.graph.ros2.graph import Ros2Graph
from rostool.graph.ros2_base.names import topic_to_dds
from rostool.graph.ros2.services import ServiceServer
from rostool.interfaces.fill import build_message

PERIOD = float(sys.argv[2])
graph = Ros2Graph("robo", anonymous=False, interface_paths=[sys.argv[1]])
session, types, store = graph.session, graph.types, graph.types.store
T = register_action(types, "robo_msgs/action/Count")
feedback_writer = session.writer(topic_to_dds("/count/_action/feedback"), T.feedback_message, FEEDBACK_QOS)
goals = {}

def rate(request):
    parts = request.status.parts
    summary = f"{request.status.name}: {len(parts)} parts, {sum(p.weight for p in parts):g} kg"
    fields = {"score": request.factor * len(parts), "summary": summary}
    return build_message(store, "robo_msgs/srv/Rate_Response", fields)

def execute(gid, goal):
    for step in range(goal["count"]):
        if goal["cancel"].is_set():
            goal["status"] = 5
            break
        goal["done_steps"].append(step)
        fields = {"goal_id": {"uuid": list(gid)},
                  "feedback": {"step": step, "part": {"label": goal["label"], "weight": step / 2}}}
        message = build_message(store, T.feedback_message, fields)
        ddspy_write(feedback_writer._ref, types.serialize(message, T.feedback_message))
        time.sleep(PERIOD)
    else:
        goal["status"] = 4
    goal["done"].set()

def send_goal(request):
    gid = bytes(request.goal_id.uuid)
    now = time.time_ns()
    stamp = {"sec": now // 10**9, "nanosec": now % 10**9}
    goals[gid] = {"count": int(request.goal.count), "label": request.goal.label, "status": 2, "stamp": stamp,
                  "done_steps": [], "done": threading.Event(), "cancel": threading.Event()}
    print("GOAL", gid.hex(), request.goal.count, request.goal.label, flush=True)
    threading.Thread(target=execute, args=(gid, goals[gid]), daemon=True).start()
    return build_message(store, T.send_goal + "_Response", {"accepted": True, "stamp": stamp})

def get_result(request):
    goal = goals[bytes(request.goal_id.uuid)]
    goal["done"].wait()
    fields = {"status": goal["status"], "result": {"done": goal["done_steps"]}}
    return build_message(store, T.get_result + "_Response", fields)

def cancel_goal(request):
    gid = bytes(request.goal_info.goal_id.uuid)
    active = [g for g, goal in goals.items() if not goal["done"].is_set()]
    targets = active if gid == bytes(16) else [gid] if gid in active else []
    code = 0 if targets else 1 if gid == bytes(16) else 2 if gid not in goals else 3
    print("CANCEL", gid.hex(), code, *[t.hex() for t in targets], flush=True)
    for target in targets:
        goals[target]["cancel"].set()
    canceling = [{"goal_id": {"uuid": list(t)}, "stamp": goals[t]["stamp"]} for t in targets]
    fields = {"return_code": code, "goals_canceling": canceling}
    return build_message(store, "action_msgs/srv/CancelGoal_Response", fields)

servers = [
    ServiceServer(session, "/rate", "robo_msgs/srv/Rate", rate),
    ServiceServer(session, "/count/_action/send_goal", T.send_goal, send_goal),
    ServiceServer(session, "/count/_action/get_result", T.get_result, get_result),
    ServiceServer(session, "/count/_action/cancel_goal", "action_msgs/srv/CancelGoal", cancel_goal),
]
print("ready", flush=True)
sys.stdin.read()
for server in servers:
    server.close()
graph.close()
"""


@pytest.fixture
def sources(tmp_path: Path) -> Path:
    return interface_workspace(tmp_path, SOURCES)


def start_robo(sources: Path, period: float) -> tuple[subprocess.Popen[str], dict[str, str]]:
    env = ros2_env()
    proc = subprocess.Popen(
        [sys.executable, "-c", ROBO_NODE, str(sources), str(period)], env=env, stdin=subprocess.PIPE,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert proc.stdout is not None
    assert proc.stdout.readline() == "ready\n", proc.stderr.read() if proc.stderr else ""
    return proc, env


@pytest.fixture
def robo(sources: Path) -> Iterator[tuple[subprocess.Popen[str], dict[str, str]]]:
    proc, env = start_robo(sources, 0.05)
    yield proc, env
    proc.communicate(input="", timeout=20)


REQUEST = "{status: {name: r2, parts: [{label: arm, weight: 1.5}, {label: wheel, weight: 2}]}, factor: 4}"


def test_service_call_with_a_custom_type(
    robo: tuple[subprocess.Popen[str], dict[str, str]], sources: Path
) -> None:
    _server, env = robo
    given = rostool(["service", "call", "/rate", "robo_msgs/srv/Rate", REQUEST, "--interfaces", str(sources),
                     "--json"], env)  # fmt: skip
    assert given.returncode == 0, given.stderr
    assert json.loads(given.stdout) == {"score": 8, "summary": "r2: 2 parts, 3.5 kg"}

    # the type the server announces, found in the sources; request fields in order; ros2 service call's text
    announced = rostool(
        ["service", "call", "/rate", "{name: solo, parts: [{label: x, weight: 0.25}]}", "3"],
        {**env, "ROSTOOL_INTERFACES": str(sources)},
    )
    assert announced.returncode == 0, announced.stderr
    assert announced.stdout.startswith(
        "requester: making request: robo_msgs.srv.Rate_Request(status=robo_msgs.msg.Status(name='solo', "
        "parts=[robo_msgs.msg.Part(label='x', weight=0.25)], where=geometry_msgs.msg.Point(x=0.0, y=0.0, "
        "z=0.0)), factor=3)\n"
    )
    assert (
        "response:\nrobo_msgs.srv.Rate_Response(score=3, summary='solo: 1 parts, 0.25 kg')\n"
        in announced.stdout
    )

    listed = rostool(["service", "list", "-t"], env)
    assert listed.stdout == "/rate [robo_msgs/srv/Rate]\n", listed.stderr

    unknown = rostool(["service", "call", "/rate", "robo_msgs/srv/Rate", REQUEST], env)
    assert unknown.returncode == 1 and unknown.stderr.count("\n") == 1
    assert "unknown service type 'robo_msgs/srv/Rate': searched rosbags' built-in ROS 2 jazzy type store" in (
        unknown.stderr
    )
    assert "no package robo_msgs in the sources" in unknown.stderr and "--interfaces" in unknown.stderr
    missing = rostool(
        ["service", "call", "/rate", "robo_msgs/srv/Nope", "{}", "--interfaces", str(sources)], env
    )
    assert missing.returncode == 1
    assert f"--interfaces {sources}" in missing.stderr
    assert f"package robo_msgs (at {sources / 'robo_msgs'}) has no srv/Nope.srv" in missing.stderr


def test_service_info(robo: tuple[subprocess.Popen[str], dict[str, str]]) -> None:
    _server, env = robo
    info = rostool(["service", "info", "/rate"], env)
    assert info.stdout == "Type: robo_msgs/srv/Rate\nClients count: 0\nServices count: 1\n", info.stderr

    verbose = rostool(["service", "info", "rate", "-v"], env)
    lines = verbose.stdout.splitlines()
    assert lines[:4] == ["Type: robo_msgs/srv/Rate", "Clients count: 0", "", "Services count: 1"], (
        verbose.stderr
    )
    assert lines[5:11] == [
        "Node name: robo", "Node namespace: /", "Service type: robo_msgs/srv/Rate",
        f"Service type hash: {lines[8].split(': ')[1]}", "Endpoint type: SERVER", "Endpoint count: 2",
    ]  # fmt: skip
    assert lines[8].startswith("Service type hash: RIHS01_")
    assert lines[11] == "GIDs:" and lines[12].startswith(" - Request Reader : ")
    assert "      Reliability: RELIABLE" in lines and "      Durability: VOLATILE" in lines

    found = json.loads(rostool(["service", "info", "/rate", "--json"], env).stdout)
    assert found["types"] == ["robo_msgs/srv/Rate"] and found["clients"] == []
    assert [(s["node"], s["endpoint_type"], sorted(s["endpoints"])) for s in found["servers"]] == [
        ("/robo", "SERVER", ["reply", "request"])
    ]
    assert found["servers"][0]["endpoints"]["request"]["is_writer"] is False

    missing = rostool(["service", "info", "/nope"], env)
    assert missing.returncode == 1 and "unknown service /nope" in missing.stderr


def test_action_send_goal_with_a_custom_type(
    robo: tuple[subprocess.Popen[str], dict[str, str]], sources: Path
) -> None:
    server, env = robo
    goal = "{count: 3, label: bolt}"
    argv = ["action", "send-goal", "/count", "robo_msgs/action/Count", goal, "--feedback", "--json",
            "--interfaces", str(sources)]  # fmt: skip
    done = rostool(argv, env)
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in done.stdout.splitlines()]
    assert events[0]["event"] == "sent" and events[0]["goal"] == {"count": 3, "label": "bolt"}
    assert [e["feedback"] for e in events if e["event"] == "feedback"] == [
        {"step": step, "part": {"label": "bolt", "weight": step / 2}} for step in range(3)
    ]
    assert events[-1] == {"event": "result", "status": "SUCCEEDED", "result": {"done": [0, 1, 2]}}
    assert server.stdout is not None
    assert server.stdout.readline() == f"GOAL {events[0]['goal_id']} 3 bolt\n"

    listed = rostool(["action", "list", "-t"], env)
    assert listed.stdout == "/count [robo_msgs/action/Count]\n", listed.stderr
    # the type from the graph, the sources from the environment
    text = rostool(["action", "send-goal", "/count", "{label: nut}"],
                   {**env, "ROSTOOL_INTERFACES": str(sources)})  # fmt: skip
    assert text.returncode == 0, text.stderr
    waiting = "Waiting for an action server to become available...\n"  # ros2 action send_goal's first line
    assert text.stdout.startswith(f"{waiting}Sending goal:\n     count: 2\nlabel: nut\n\n"), text.stdout
    assert text.stdout.endswith("Result:\n    done:\n- 0\n- 1\n\nGoal finished with status: SUCCEEDED\n")

    unknown = rostool(["action", "send-goal", "/count", "{count: 1}"], env)
    assert unknown.returncode == 1
    assert "unknown action type 'robo_msgs/action/Count'" in unknown.stderr
    builtin = "built-in action types (example_interfaces/action/Fibonacci, test_msgs/action/Fibonacci)"
    assert builtin in unknown.stderr


def test_action_cancel_one_goal_then_all(sources: Path) -> None:
    server, env = start_robo(sources, 0.2)
    env = {**env, "ROSTOOL_INTERFACES": str(sources)}
    clients: list[subprocess.Popen[str]] = []
    try:
        ids = []
        for label in ("first", "second"):
            # 40 s of steps: under load the clients and cancels that follow took most of a 10 s goal, which
            # then finished before its cancel came ("the goal already finished", in a full run)
            goal = f"{{count: 200, label: {label}}}"
            client = rostool_popen(["action", "send-goal", "/count", goal, "--json", "--feedback"], env)
            clients.append(client)
            assert client.stdout is not None
            ids.append(json.loads(client.stdout.readline())["goal_id"])
            assert json.loads(client.stdout.readline())["event"] == "feedback"

        one = rostool(["action", "cancel", "/count", ids[0]], env)
        assert one.stdout == f"Canceling 1 goal(s) of /count:\n    {ids[0]}\n", one.stderr
        first_out, first_err = clients[0].communicate(timeout=15)
        assert clients[0].returncode == 1, first_err
        result = json.loads(first_out.splitlines()[-1])
        assert result["event"] == "result" and result["status"] == "CANCELED"

        again = rostool(["action", "cancel", "/count", ids[0]], env)
        assert again.returncode == 1
        assert (
            again.stderr == f"rostool: canceling goal {ids[0]} of /count failed: the goal already finished\n"
        )

        every = rostool(["action", "cancel", "count", "--json"], env)
        assert every.returncode == 0, every.stderr
        canceled = json.loads(every.stdout)
        assert [g["goal_id"] for g in canceled["goals_canceling"]] == [ids[1]]
        assert canceled["action"] == "/count" and canceled["goals_canceling"][0]["stamp"]["sec"] > 0
        second_out, _ = clients[1].communicate(timeout=15)
        assert json.loads(second_out.splitlines()[-1])["status"] == "CANCELED"

        nothing = rostool(["action", "cancel", "/count"], env)
        assert nothing.returncode == 1
        assert (
            "canceling every goal of /count failed: the server rejected the cancel request" in nothing.stderr
        )
        bad = rostool(["action", "cancel", "/count", "xyz"], env)
        assert bad.returncode == 1 and "bad goal id 'xyz'" in bad.stderr
    finally:
        for client in clients:
            stop(client)
        server_out, server_err = server.communicate(input="", timeout=20)
    lines = server_out.splitlines()
    assert f"CANCEL {ids[0]} 0 {ids[0]}" in lines, server_err
    assert f"CANCEL {'00' * 16} 0 {ids[1]}" in lines
    assert f"CANCEL {'00' * 16} 1" in lines


def test_custom_message_pub_echo(sources: Path) -> None:
    env = ros2_env()
    status = "{parts: [{label: arm, weight: 1.5}, {label: leg}], where: {x: 1.0, y: -2.0}}"
    publisher = rostool_popen(["topic", "pub", "/status", "robo_msgs/msg/Status", status, "-r", "10",
                               "--interfaces", str(sources)], env)  # fmt: skip
    try:
        echo = rostool(["topic", "echo", "/status", "-n", "2", "--json"],
                       {**env, "ROSTOOL_INTERFACES": str(sources)}, timeout=40)  # fmt: skip
        assert echo.returncode == 0, echo.stderr
        parts = [{"label": "arm", "weight": 1.5}, {"label": "leg", "weight": 0.5}]  # 0.5: the default
        expected = {"name": "un#named", "parts": parts, "where": {"x": 1.0, "y": -2.0, "z": 0.0}}
        assert [json.loads(line) for line in echo.stdout.splitlines()] == [expected, expected]

        typed = rostool(["topic", "type", "/status"], env)
        assert typed.stdout == "robo_msgs/msg/Status\n", typed.stderr

        # without the sources: the type comes from the publisher's type description service
        blind = rostool(["topic", "echo", "/status", "-n", "1", "--json", "--timeout", "5"], env)
        assert blind.returncode == 0, blind.stderr
        assert json.loads(blind.stdout) == expected
    finally:
        _out, err = stop(publisher)
    assert "Traceback" not in err, err
