"""ROS 2 actions (rcl_action's services and topics) against a Fibonacci action server built on rostool's
library (FIB_SERVER below): send-goal with feedback, list/info, Ctrl+C canceling the goal on the server."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator

import pytest

from tests.support import rostool, rostool_popen, stop
from tests.test_ros2_graph import ros2_env

# example_interfaces/action/Fibonacci as the ROS 2 tutorial's server computes it: feedback after each new
# number, one step every PERIOD seconds (argv[1]). It prints what it does so tests see the server's side.
FIB_SERVER = r"""
import sys, threading, time
from cyclonedds._clayer import ddspy_write
from rostool.graph.ros2.actions import FEEDBACK_QOS, STATUS_ARRAY, STATUS_QOS
from rostool.interfaces.ros2_action import register_action
from rostool.graph.ros2.graph import Ros2Graph
from rostool.graph.ros2_base.names import topic_to_dds
from rostool.graph.ros2.services import ServiceServer
from rostool.interfaces.fill import build_message

PERIOD = float(sys.argv[1])
graph = Ros2Graph("fibonacci_server", anonymous=False)
session, types, store = graph.session, graph.types, graph.types.store
T = register_action(types, "example_interfaces/action/Fibonacci")
feedback_topic = topic_to_dds("/fibonacci/_action/feedback")
feedback_writer = session.writer(feedback_topic, T.feedback_message, FEEDBACK_QOS)
status_writer = session.writer(topic_to_dds("/fibonacci/_action/status"), STATUS_ARRAY, STATUS_QOS)
goals = {}

def write(writer, type_name, fields):
    ddspy_write(writer._ref, types.serialize(build_message(store, type_name, fields), type_name))

def publish_status():
    entries = [{"goal_info": {"goal_id": {"uuid": list(gid)}}, "status": goal["status"]}
               for gid, goal in goals.items()]
    write(status_writer, STATUS_ARRAY, {"status_list": entries})

def execute(gid, goal):
    sequence = [0, 1]
    for _ in range(1, goal["order"]):
        if goal["cancel"].is_set():
            goal["status"] = 5
            print("CANCELED", gid.hex(), sequence, flush=True)
            break
        sequence.append(sequence[-1] + sequence[-2])
        fields = {"goal_id": {"uuid": list(gid)}, "feedback": {"sequence": sequence}}
        write(feedback_writer, T.feedback_message, fields)
        time.sleep(PERIOD)
    else:
        goal["status"] = 4
    goal["sequence"] = sequence
    goal["done"].set()
    publish_status()

def send_goal(request):
    gid, order = bytes(request.goal_id.uuid), int(request.goal.order)
    accepted = order >= 0
    print("GOAL", gid.hex(), order, accepted, flush=True)
    if accepted:
        goals[gid] = {"order": order, "status": 2, "done": threading.Event(), "cancel": threading.Event()}
        publish_status()
        threading.Thread(target=execute, args=(gid, goals[gid]), daemon=True).start()
    now = time.time_ns()
    stamp = {"sec": now // 10**9, "nanosec": now % 10**9}
    return build_message(store, T.send_goal + "_Response", {"accepted": accepted, "stamp": stamp})

def get_result(request):
    goal = goals.get(bytes(request.goal_id.uuid))
    if goal is None:
        return build_message(store, T.get_result + "_Response", {"status": 0})
    goal["done"].wait()
    fields = {"status": goal["status"], "result": {"sequence": goal["sequence"]}}
    return build_message(store, T.get_result + "_Response", fields)

def cancel_goal(request):
    gid = bytes(request.goal_info.goal_id.uuid)
    goal = goals.get(gid)
    code = 2 if goal is None else 3 if goal["done"].is_set() else 0
    print("CANCEL REQUEST", gid.hex(), code, flush=True)
    if code == 0:
        goal["status"] = 3
        goal["cancel"].set()
        publish_status()
    canceling = [{"goal_id": {"uuid": list(gid)}}] if code == 0 else []
    fields = {"return_code": code, "goals_canceling": canceling}
    return build_message(store, "action_msgs/srv/CancelGoal_Response", fields)

servers = [
    ServiceServer(session, "/fibonacci/_action/send_goal", T.send_goal, send_goal),
    ServiceServer(session, "/fibonacci/_action/get_result", T.get_result, get_result),
    ServiceServer(session, "/fibonacci/_action/cancel_goal", "action_msgs/srv/CancelGoal", cancel_goal),
]
print("ready", flush=True)
sys.stdin.read()
for server in servers:
    server.close()
graph.close()
"""


def start_server(period: float) -> tuple[subprocess.Popen[str], dict[str, str]]:
    env = ros2_env()
    proc = subprocess.Popen(
        [sys.executable, "-c", FIB_SERVER, str(period)], env=env, stdin=subprocess.PIPE,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert proc.stdout is not None
    assert proc.stdout.readline() == "ready\n", proc.stderr.read() if proc.stderr else ""
    return proc, env


@pytest.fixture
def fibonacci() -> Iterator[tuple[subprocess.Popen[str], dict[str, str]]]:
    proc, env = start_server(0.05)
    yield proc, env
    proc.communicate(input="", timeout=20)


def test_send_goal_feedback_and_result(fibonacci: tuple[subprocess.Popen[str], dict[str, str]]) -> None:
    server, env = fibonacci
    fib = "example_interfaces/action/Fibonacci"
    done = rostool(["action", "send-goal", "/fibonacci", fib, "{order: 5}", "--feedback", "--json"], env)
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in done.stdout.splitlines()]
    assert events[0]["event"] == "sent" and events[0]["accepted"] is True
    assert events[0]["goal"] == {"order": 5}
    feedback = [e["feedback"]["sequence"] for e in events if e["event"] == "feedback"]
    assert feedback == [[0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3], [0, 1, 1, 2, 3, 5]]
    assert events[-1] == {"event": "result", "status": "SUCCEEDED", "result": {"sequence": feedback[-1]}}
    assert server.stdout is not None
    assert server.stdout.readline() == f"GOAL {events[0]['goal_id']} 5 True\n"

    # ros2 action send_goal's text; the type from the graph (pkg/Type also works)
    text = rostool(["action", "send-goal", "fibonacci", "{order: 3}", "--feedback"], env)
    assert text.returncode == 0, text.stderr
    goal_id = server.stdout.readline().split()[1]
    assert text.stdout == (
        "Waiting for an action server to become available...\n"  # ros2 prints it first, always
        f"Sending goal:\n     order: 3\n\nGoal accepted with ID: {goal_id}\n\n"
        "Feedback:\n    sequence:\n- 0\n- 1\n- 1\n\n"
        "Feedback:\n    sequence:\n- 0\n- 1\n- 1\n- 2\n\n"
        "Result:\n    sequence:\n- 0\n- 1\n- 1\n- 2\n\n"
        "Goal finished with status: SUCCEEDED\n"
    )
    quiet = rostool(["action", "send-goal", "/fibonacci", "example_interfaces/Fibonacci", "2", "--json"], env)
    kinds = [json.loads(line)["event"] for line in quiet.stdout.splitlines()]
    assert kinds == ["sent", "result"], quiet.stderr
    assert json.loads(quiet.stdout.splitlines()[-1])["result"] == {"sequence": [0, 1, 1]}

    rejected = rostool(["action", "send-goal", "/fibonacci", "{order: -1}"], env)
    assert rejected.returncode == 1 and rejected.stdout.endswith("Goal was rejected.\n"), rejected.stderr


def test_list_info(fibonacci: tuple[subprocess.Popen[str], dict[str, str]]) -> None:
    _server, env = fibonacci
    assert rostool(["action", "list"], env).stdout == "/fibonacci\n"
    listed = rostool(["action", "list", "-t"], env)
    assert listed.stdout == "/fibonacci [example_interfaces/action/Fibonacci]\n", listed.stderr
    info = rostool(["action", "info", "/fibonacci"], env)
    assert info.stdout.splitlines() == [
        "Action: /fibonacci", "Action clients: 0",
        "Action servers: 1", "    /fibonacci_server",
    ], info.stderr  # fmt: skip
    assert json.loads(rostool(["action", "info", "/fibonacci", "--json"], env).stdout)["servers"] == [
        "/fibonacci_server"
    ]
    # the hidden services are actions' business, not `service list`'s
    assert rostool(["service", "list"], env).stdout == ""
    hidden = rostool(["service", "list", "-a"], env).stdout.splitlines()
    assert "/fibonacci/_action/send_goal" in hidden and len(hidden) == 3
    missing = rostool(["action", "info", "/nope"], env)  # ros2 action info's lines, then the error
    assert missing.stdout == "Action: /nope\nAction clients: 0\nAction servers: 0\n"
    assert missing.returncode == 1 and "unknown action /nope" in missing.stderr


def test_ctrl_c_cancels_the_goal_on_the_server() -> None:
    server, env = start_server(0.2)
    try:
        argv = ["action", "send-goal", "/fibonacci", "{order: 40}", "--feedback", "--json"]
        client = rostool_popen(argv, env)
        assert client.stdout is not None
        sent = json.loads(client.stdout.readline())
        assert sent["event"] == "sent" and sent["accepted"] is True
        assert json.loads(client.stdout.readline())["feedback"]["sequence"] == [0, 1, 1]
        out, err = stop(client, timeout=15)
        assert client.returncode == 130, err
        events = [json.loads(line) for line in out.splitlines()]
        assert {"event": "canceling", "goal_id": sent["goal_id"]} in events
        assert events[-1]["event"] == "result" and events[-1]["status"] == "CANCELED"
        partial = events[-1]["result"]["sequence"]
        assert partial[:3] == [0, 1, 1] and len(partial) < 41

        late = rostool(["action", "send-goal", "/fibonacci", "{order: 40}", "--timeout", "1"], env)
        assert late.returncode == 1 and "Canceling goal..." in late.stdout
        late_id = late.stderr.split()[2]
        assert late.stderr == f"rostool: goal {late_id} got no result within 1 s; canceled it\n"
    finally:
        server_out, server_err = server.communicate(input="", timeout=20)
    lines = server_out.splitlines()
    assert f"GOAL {sent['goal_id']} 40 True" in lines, server_err
    assert f"CANCEL REQUEST {sent['goal_id']} 0" in lines
    assert f"CANCELED {sent['goal_id']} {partial}" in lines  # the server stopped where the client saw it
    assert f"CANCEL REQUEST {late_id} 0" in lines


def test_cancel_by_goal_id() -> None:
    server, env = start_server(0.2)
    try:
        client = rostool_popen(["action", "send-goal", "/fibonacci", "{order: 40}", "--json"], env)
        assert client.stdout is not None
        sent = json.loads(client.stdout.readline())
        assert sent["event"] == "sent" and sent["accepted"] is True, client.stderr
        goal_id = sent["goal_id"]

        canceled = rostool(["action", "cancel", "/fibonacci", goal_id], env)
        assert canceled.stdout == f"Canceling 1 goal(s) of /fibonacci:\n    {goal_id}\n", canceled.stderr
        out, err = client.communicate(timeout=15)
        assert client.returncode == 1, err
        result = json.loads(out.splitlines()[-1])
        assert result["status"] == "CANCELED" and result["result"]["sequence"][:2] == [0, 1]

        stranger = "0123456789abcdef0123456789abcdef"
        unknown = rostool(["action", "cancel", "/fibonacci", stranger], env)
        assert unknown.returncode == 1
        assert unknown.stderr == (
            f"rostool: canceling goal {stranger} of /fibonacci failed: the server does not know the goal\n"
        )
    finally:
        server_out, server_err = server.communicate(input="", timeout=20)
    lines = server_out.splitlines()
    assert f"CANCEL REQUEST {goal_id} 0" in lines, server_err
    assert any(line.startswith(f"CANCELED {goal_id} [0, 1") for line in lines)
    assert f"CANCEL REQUEST {stranger} 2" in lines
