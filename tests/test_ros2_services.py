"""ROS 2 services and parameters over rmw_cyclonedds_cpp's request/reply convention.

The peer is a small ROS 2 node built on rostool's own library (DEMO_NODE below): it serves the four
rcl_interfaces parameter services of a node `/demo` and example_interfaces/AddTwoInts on `/add_two_ints`.
The parameter verbs' tests (tests/test_ros2_params.py) run against the same node through `demo_node()`.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from tests.support import rostool
from tests.test_ros2_graph import ros2_env

DEMO_NODE = r"""
import sys
from rostool.graph.ros2_base import params as P
from rostool.graph.ros2.graph import Ros2Graph
from rostool.graph.ros2.services import ServiceServer
from rostool.interfaces.fill import build_message

graph = Ros2Graph("demo", anonymous=False)
session, store = graph.session, graph.types.store
initial = {"use_sim_time": False, "speed": 1.5, "robot_name": "r2", "wheels": 4, "tags": ["a", "b"],
           "limits.max_speed": 3.0, "limits.min_speed": 0.5}
values = {name: (P.type_of(value), value) for name, value in initial.items()}  # name -> (type, value)
read_only = {"wheels"}

def reply(srv, fields):
    return build_message(store, f"rcl_interfaces/srv/{srv}_Response", fields)

def list_parameters(request):
    return reply("ListParameters", {"result": {"names": sorted(values)}})

def get_parameters(request):
    found = [P.typed_fields(*values.get(n, (P.NOT_SET, None))) for n in request.names]
    return reply("GetParameters", {"values": found})

def set_one(name, value):
    # as rclcpp judges one parameter: read-only ones are refused, NOT_SET undeclares (deletes)
    if name in read_only:
        return {"successful": False, "reason": f"parameter '{name}' cannot be set because it is read-only"}
    if int(value.type) == P.NOT_SET:
        values.pop(name, None)
    else:
        values[name] = (int(value.type), P.to_python(value))
    return {"successful": True}

def set_parameters(request):
    return reply("SetParameters", {"results": [set_one(p.name, p.value) for p in request.parameters]})

def describe_parameters(request):
    return reply("DescribeParameters", {"descriptors": [
        {"name": n, "type": values.get(n, (P.NOT_SET,))[0], "description": f"the {n}",
         "read_only": n in read_only}
        for n in request.names]})

def add_two_ints(request):
    return build_message(store, "example_interfaces/srv/AddTwoInts_Response", {"sum": request.a + request.b})

servers = [
    ServiceServer(session, f"/demo/{name}", "rcl_interfaces/srv/" + name.title().replace("_", ""), handler)
    for name, handler in (("list_parameters", list_parameters), ("get_parameters", get_parameters),
                          ("set_parameters", set_parameters), ("describe_parameters", describe_parameters))
]
servers.append(ServiceServer(session, "/add_two_ints", "example_interfaces/srv/AddTwoInts", add_two_ints))
print("ready", flush=True)
sys.stdin.read()
for server in servers:
    server.close()
graph.close()
"""

# Calls /add_two_ints through rostool's library and prints the sum (a second process as the client).
CALL_ADD = r"""
import sys
from rostool.graph.ros2.graph import Ros2Graph
with Ros2Graph() as graph:
    print(graph.call_service("/add_two_ints", "example_interfaces/srv/AddTwoInts", {"a": 40, "b": 2}).sum)
    print(graph.services())
"""


@contextmanager
def demo_node() -> Iterator[dict[str, str]]:
    """DEMO_NODE running on a domain of its own; yields the environment that reaches it."""
    env = ros2_env()
    proc = subprocess.Popen(
        [sys.executable, "-c", DEMO_NODE], env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert proc.stdout is not None
    assert proc.stdout.readline() == "ready\n", proc.stderr.read() if proc.stderr else ""
    try:
        yield env
    finally:
        proc.communicate(input="", timeout=20)


@pytest.fixture
def demo() -> Iterator[dict[str, str]]:
    with demo_node() as env:
        yield env


def test_service_call_and_node_info(demo: dict[str, str]) -> None:
    argv = [sys.executable, "-c", CALL_ADD]
    call = subprocess.run(argv, env=demo, capture_output=True, text=True, timeout=60)
    lines = call.stdout.splitlines()
    assert lines[0] == "42", call.stderr
    assert "('/add_two_ints', 'example_interfaces/srv/AddTwoInts', ['/demo'])" in lines[1]
    info = json.loads(rostool(["node", "info", "/demo", "--json"], demo).stdout)
    servers = info["service_servers"]
    assert {"name": "/add_two_ints", "type": "example_interfaces/srv/AddTwoInts"} in servers
    assert {"name": "/demo/get_parameters", "type": "rcl_interfaces/srv/GetParameters"} in servers


def test_service_verbs_ros2_forms(demo: dict[str, str]) -> None:
    """ros2 service list/type/find/call against the demo node, values computed by the server."""
    listed = rostool(["service", "list"], demo)
    assert listed.stdout.splitlines() == [
        "/add_two_ints", "/demo/describe_parameters", "/demo/get_parameters", "/demo/list_parameters",
        "/demo/set_parameters",
    ], listed.stderr  # fmt: skip
    typed = rostool(["service", "list", "-t", "/demo"], demo).stdout.splitlines()
    assert typed[1] == "/demo/get_parameters [rcl_interfaces/srv/GetParameters]" and len(typed) == 4
    as_json = json.loads(rostool(["service", "list", "--json"], demo).stdout)
    add_type = "example_interfaces/srv/AddTwoInts"
    assert as_json[0] == {"name": "/add_two_ints", "type": add_type, "nodes": ["/demo"]}
    assert rostool(["service", "type", "add_two_ints"], demo).stdout == "example_interfaces/srv/AddTwoInts\n"
    assert rostool(["service", "find", "example_interfaces/AddTwoInts"], demo).stdout == "/add_two_ints\n"

    full = ["service", "call", "/add_two_ints", "example_interfaces/srv/AddTwoInts", "{a: 40, b: 2}"]
    called = rostool(full, demo)
    assert called.stdout == (
        "requester: making request: example_interfaces.srv.AddTwoInts_Request(a=40, b=2)\n\n"
        "response:\nexample_interfaces.srv.AddTwoInts_Response(sum=42)\n\n"
    ), called.stderr
    # the type from the graph; pkg/Type; values in field order; --json
    discovered = rostool(["service", "call", "/add_two_ints", "{a: 7, b: -2}", "--json"], demo)
    assert json.loads(discovered.stdout) == {"sum": 5}, discovered.stderr
    in_order = ["service", "call", "add_two_ints", "example_interfaces/AddTwoInts", "-3", "4", "--json"]
    short = rostool(in_order, demo)
    assert json.loads(short.stdout) == {"sum": 1}, short.stderr
    params = ["service", "call", "/demo/get_parameters", "{names: [robot_name]}", "--json"]
    assert json.loads(rostool(params, demo).stdout)["values"][0]["string_value"] == "r2"

    wrong = rostool(["service", "call", "/add_two_ints", "5"], demo)
    assert wrong.returncode == 1 and wrong.stdout == ""
    assert "AddTwoInts takes 2 request value(s) in this order: a b; got 1" in wrong.stderr
    absent = rostool(["service", "call", "/nope"], demo)
    assert absent.returncode == 1 and "unknown service /nope: no server announces it" in absent.stderr
    no_server = rostool(["service", "call", "/nope", "std_srvs/srv/Trigger", "--timeout", "1"], demo)
    assert no_server.returncode == 1
    assert "service /nope is not available: no server matched within 1 s" in no_server.stderr
