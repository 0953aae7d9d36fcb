"""`rostool service` and `srv` against Debian's rosmaster, rospy service servers, rosservice and rossrv."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support import (
    debian,
    interface_workspace,
    master_names,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
    wait_until,
    with_genpy_classes,
)

SUM_SRV = "int64 a\nint64 b\n---\nint64 sum\n"

# The book's server (Ch18), printing what it serves so tests see real values on both sides.
SUM_SERVER = """
import rospy
from sum_two_numbers.srv import SumTwoInts, SumTwoIntsResponse
def handle_sum(req):
    print("REQUEST %d %d" % (req.a, req.b), flush=True)
    return SumTwoIntsResponse(req.a + req.b)
rospy.init_node('sum_server')
rospy.Service('sum_two_ints', SumTwoInts, handle_sum)
print("READY", flush=True)
rospy.spin()
"""

STD_SRVS_SERVER = """
import rospy
from std_srvs.srv import Empty, EmptyResponse, SetBool, SetBoolResponse, Trigger, TriggerResponse
state = {"enabled": False, "resets": 0}
def reset(_req):
    state["resets"] += 1
    print("RESET %d" % state["resets"], flush=True)
    return EmptyResponse()
def enable(req):
    state["enabled"] = req.data
    print("ENABLED %s" % req.data, flush=True)
    return SetBoolResponse(True, "enabled" if req.data else "disabled")
def trigger(_req):
    return TriggerResponse(state["enabled"], "resets=%d enabled=%s" % (state["resets"], state["enabled"]))
rospy.init_node('std_server')
rospy.Service('reset', Empty, reset)
rospy.Service('set_enabled', SetBool, enable)
rospy.Service('status', Trigger, trigger)
print("READY", flush=True)
rospy.spin()
"""

# A server that exits in the middle of a call, and one that answers too late.
DYING_SERVER = """
import os, time, rospy
from sum_two_numbers.srv import SumTwoInts
def handle(req):
    if req.a < 0:
        os._exit(3)
    time.sleep(req.a)
    return req.a + req.b
rospy.init_node('flaky_server')
rospy.Service('flaky', SumTwoInts, handle)
print("READY", flush=True)
rospy.spin()
"""

# rostool's own small server (library), so Debian's rosservice has something of ours to call.
OUR_SERVER = """
import sys, time
from rostool.graph.ros1.node import Node
from rostool.graph.ros1.services import ServiceServer
from rostool.interfaces.sources import interfaces
from rostool.interfaces.srv import load_service
srv = load_service(interfaces([sys.argv[1]]), "sum_two_numbers/SumTwoInts")
with Node("our_sum_server", anonymous=False) as node:
    server = ServiceServer(node, "/our_sum", srv, lambda req: srv.response.message_class()(sum=req.a + req.b))
    print("READY", flush=True)
    try:
        while True:
            time.sleep(1)
    except KeyboardInterrupt:
        server.close()
"""


@pytest.fixture
def sum_env(debian_master: dict[str, str], tmp_path: Path) -> dict[str, str]:
    """The book's sum_two_numbers package as a source tree, with genpy classes for the rospy server."""
    src = interface_workspace(tmp_path / "catkin_ws", {"sum_two_numbers/srv/SumTwoInts.srv": SUM_SRV})
    return with_genpy_classes(debian_master, src, tmp_path)


def _start(source: str, env: dict[str, str], tmp_path: Path, name: str) -> subprocess.Popen[str]:
    proc = start_rospy_script(source, env, tmp_path, name)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line.strip() == "READY", proc.stderr.read() if proc.stderr else line
    return proc


def _wait_service(env: dict[str, str], name: str) -> None:
    """Until the master knows service `name` (asked in process), then rostool's list must show it."""
    assert wait_until(lambda: name in master_names(env["ROS_MASTER_URI"])["services"], 20), name
    listed = rostool(["service", "list"], env)
    assert name in listed.stdout.split(), listed.stderr


def _book_w11(env: dict[str, str], tmp_path: Path) -> None:
    server = _start(SUM_SERVER, env, tmp_path, "server")
    try:
        _wait_service(env, "/sum_two_ints")
        ours_list, theirs_list = rostool(["service", "list"], env), debian(["rosservice", "list"], env)
        assert "/sum_two_ints" in ours_list.stdout.split()
        assert ours_list.stdout == theirs_list.stdout
        assert rostool(["service", "type", "/sum_two_ints"], env).stdout == "sum_two_numbers/SumTwoInts\n"
        assert debian(["rosservice", "type", "/sum_two_ints"], env).stdout == "sum_two_numbers/SumTwoInts\n"
        ours_show = rostool(["srv", "show", "sum_two_numbers/SumTwoInts"], env).stdout
        assert ours_show == debian(["rossrv", "show", "sum_two_numbers/SumTwoInts"], env).stdout
        assert ours_show == "int64 a\nint64 b\n---\nint64 sum\n\n"
        ours = rostool(["service", "call", "/sum_two_ints", "7", "8"], env)
        assert ours.stdout == "sum: 15\n", ours.stderr
        assert ours.stdout == debian(["rosservice", "call", "/sum_two_ints", "7", "8"], env).stdout
    finally:
        out, _err = stop(server)
    assert "REQUEST 7 8" in out


def test_book_w11_sum_of_two_numbers(debian_roscore: dict[str, str], tmp_path: Path) -> None:
    src = interface_workspace(tmp_path / "catkin_ws", {"sum_two_numbers/srv/SumTwoInts.srv": SUM_SRV})
    _book_w11(with_genpy_classes(debian_roscore, src, tmp_path), tmp_path)


def test_list_info_uri_find_args_match_rosservice(sum_env: dict[str, str], tmp_path: Path) -> None:
    env = sum_env
    server = _start(SUM_SERVER, env, tmp_path, "server")
    try:
        _wait_service(env, "/sum_two_ints")
        verbs = [["list", "-n"], ["info", "/sum_two_ints"], ["uri", "/sum_two_ints"],
                 ["node", "/sum_two_ints"], ["args", "/sum_two_ints"], ["find", "sum_two_numbers/SumTwoInts"],
                 ["type", "/sum_server/get_loggers"], ["list", "/sum_server"]]  # fmt: skip
        for verb in verbs:
            ours, theirs = rostool(["service", *verb], env), debian(["rosservice", *verb], env)
            assert ours.stdout == theirs.stdout, (verb, ours.stderr, theirs.stderr)
        info = rostool(["service", "info", "/sum_two_ints"], env).stdout
        assert info.startswith("Node: /sum_server\nURI: rosrpc://127.0.0.1:") and info.endswith("Args: a b\n")
        as_json = json.loads(rostool(["service", "info", "/sum_two_ints", "--json"], env).stdout)
        assert as_json["md5sum"] == "6a2e34150c00229791cc89ff309fff21" and as_json["args"] == ["a", "b"]
        listed = json.loads(rostool(["service", "list", "--json"], env).stdout)
        assert {"name": "/sum_two_ints", "nodes": ["/sum_server"]} in listed
        # every rospy node offers the roscpp logger services: built-in types, callable with no sources
        ours = rostool(["service", "call", "/sum_server/get_loggers"], env)
        assert ours.stdout == debian(["rosservice", "call", "/sum_server/get_loggers"], env).stdout
        assert 'name: "rospy"' in ours.stdout
    finally:
        stop(server)


def test_call_forms_json_and_sources(sum_env: dict[str, str], tmp_path: Path) -> None:
    env = sum_env
    server = _start(SUM_SERVER, env, tmp_path, "server")
    try:
        _wait_service(env, "/sum_two_ints")
        assert rostool(["service", "call", "/sum_two_ints", "{a: 7, b: 8}"], env).stdout == "sum: 15\n"
        assert rostool(["service", "call", "sum_two_ints", "-3", "5", "--json"], env).stdout == '{"sum": 2}\n'
        big = rostool(["service", "call", "/sum_two_ints", "4611686018427387904", "4611686018427387903"], env)
        assert big.stdout == "sum: 9223372036854775807\n", big.stderr
        # without ROS_PACKAGE_PATH the .srv comes from --interfaces, or from the workspace we stand in
        bare = {k: v for k, v in env.items() if k != "ROS_PACKAGE_PATH"}
        ws = tmp_path / "catkin_ws"
        assert rostool(
            ["service", "call", "/sum_two_ints", "1", "2", "--interfaces", str(ws)], bare
        ).stdout == ("sum: 3\n")
        inside = subprocess.run(
            [sys.executable, "-m", "rostool", "service", "call", "/sum_two_ints", "2", "2"],
            cwd=ws / "src" / "sum_two_numbers", env=bare, capture_output=True, text=True, timeout=30,
        )  # fmt: skip
        assert inside.stdout == "sum: 4\n", inside.stderr
        nowhere = subprocess.run(
            [sys.executable, "-m", "rostool", "service", "call", "/sum_two_ints", "2", "2"],
            cwd=tmp_path, env=bare, capture_output=True, text=True, timeout=30,
        )  # fmt: skip
        assert nowhere.returncode == 1 and nowhere.stdout == ""
        assert (
            "unknown service type sum_two_numbers/SumTwoInts: no package sum_two_numbers found"
            in nowhere.stderr
        )
        assert "Looked in:" in nowhere.stderr and len(nowhere.stderr.splitlines()) == 1
    finally:
        out, _err = stop(server)
    assert out.count("REQUEST") == 5, out  # the call that found no .srv never reached the server


def test_std_srvs_empty_trigger_setbool(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    server = _start(STD_SRVS_SERVER, env, tmp_path, "std_server")
    try:
        _wait_service(env, "/status")
        assert rostool(["service", "call", "/reset"], env).stdout == "\n"  # an empty response, as rosservice
        assert debian(["rosservice", "call", "/reset"], env).stdout == "\n"
        enabled = rostool(["service", "call", "/set_enabled", "true"], env)
        assert enabled.stdout == 'success: True\nmessage: "enabled"\n', enabled.stderr
        ours = rostool(["service", "call", "/status"], env)
        assert ours.stdout == 'success: True\nmessage: "resets=2 enabled=True"\n'
        assert ours.stdout == debian(["rosservice", "call", "/status"], env).stdout
        disabled = rostool(["service", "call", "/set_enabled", "{data: false}", "--json"], env)
        assert json.loads(disabled.stdout) == {"success": True, "message": "disabled"}
        for name, kind in (("/reset", "std_srvs/Empty"), ("/set_enabled", "std_srvs/SetBool"),
                           ("/status", "std_srvs/Trigger")):  # fmt: skip
            assert rostool(["service", "type", name], env).stdout == f"{kind}\n"
            assert rostool(["service", "find", kind], env).stdout == f"{name}\n"
        assert rostool(["service", "info", "/set_enabled"], env).stdout.endswith(
            "Type: std_srvs/SetBool\nArgs: data\n"
        )
        extra = rostool(["service", "call", "/reset", "1"], env)
        assert extra.returncode == 1 and "std_srvs/Empty takes no request values" in extra.stderr
        wrong = rostool(["service", "call", "/set_enabled", "maybe"], env)
        assert wrong.returncode == 1 and "field 'data' is a bool; got 'maybe'" in wrong.stderr
    finally:
        out, _err = stop(server)
    assert "ENABLED True" in out and "ENABLED False" in out and "RESET 2" in out


def test_bad_input_one_clear_line(sum_env: dict[str, str], tmp_path: Path) -> None:
    env = sum_env
    server = _start(SUM_SERVER, env, tmp_path, "server")
    flaky = _start(DYING_SERVER, env, tmp_path, "flaky")
    try:
        _wait_service(env, "/flaky")
        cases = {
            ("call", "/nope"): "unknown service /nope: no node provides it (see `rostool service list`)",
            ("type", "/nope"): "unknown service /nope",
            ("info", "/nope"): "unknown service /nope",
            (
                "call",
                "/sum_two_ints",
                "7",
            ): "takes 2 request value(s) in this order: a (int64), b (int64); got 1",
            ("call", "/sum_two_ints", "1", "2", "3"): "got 3",
            ("call", "/sum_two_ints"): "got none",
            ("call", "/sum_two_ints", "7", "x"): "field 'b' is an int64; got 'x' (the request of",
            ("call", "/sum_two_ints", "7.5", "1"): "field 'a' is an int64; got 7.5",
            ("call", "/sum_two_ints", "{a: 1, c: 2}"): "has no field 'c'; its fields are: a, b",
            ("call", "/sum_two_ints", "{a: [1"): "invalid YAML in value 1",
            ("call", "/flaky", "3", "0", "--timeout", "1"): "service /flaky did not answer within 1 s",
            ("call", "/flaky", "-1", "0"): "service /flaky closed the connection before answering",
        }
        for args, expected in cases.items():
            done = rostool(["service", *args], env)
            assert done.returncode == 1 and done.stdout == "", (args, done.stdout)
            assert expected in done.stderr and len(done.stderr.splitlines()) == 1, (args, done.stderr)
            assert done.stderr.startswith("rostool: ")
        # the flaky server died mid-call but is still registered: nothing answers at its address now
        flaky.wait(10)
        gone = rostool(["service", "call", "/flaky", "1", "1"], env)
        assert gone.returncode == 1 and "nothing answers there (connection refused)" in gone.stderr, (
            gone.stderr
        )
    finally:
        stop(server)
        stop(flaky)


def test_wait_for_a_service_that_comes_later(sum_env: dict[str, str], tmp_path: Path) -> None:
    env = sum_env
    call = rostool_popen(["service", "call", "/sum_two_ints", "20", "22", "--wait", "--timeout", "30"], env)
    time.sleep(1.0)
    assert call.poll() is None  # still waiting
    server = _start(SUM_SERVER, env, tmp_path, "server")
    try:
        out, err = call.communicate(timeout=30)
        assert out == "sum: 42\n", err
        late = rostool(["service", "call", "/never", "--wait", "--timeout", "0.5"], env)
        assert late.returncode == 1 and "service /never did not appear within 0.5 s" in late.stderr
    finally:
        stop(server)


def test_their_rosservice_calls_our_server(sum_env: dict[str, str], tmp_path: Path) -> None:
    env = sum_env
    script = tmp_path / "our_server.py"
    script.write_text(OUR_SERVER)
    ours = subprocess.Popen(
        [sys.executable, str(script), str(tmp_path / "catkin_ws")], env=env,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert ours.stdout is not None and ours.stdout.readline().strip() == "READY"
        assert debian(["rosservice", "type", "/our_sum"], env).stdout == "sum_two_numbers/SumTwoInts\n"
        theirs = debian(["rosservice", "call", "/our_sum", "7", "8"], env)
        assert theirs.stdout == "sum: 15\n", theirs.stderr
        assert debian(["rosservice", "info", "/our_sum"], env).stdout.startswith("Node: /our_sum_server\n")
        assert rostool(["service", "call", "/our_sum", "{a: 1, b: 1}"], env).stdout == "sum: 2\n"
        from rostool.graph.ros1.master_client import MasterClient
        from rostool.graph.ros1.services import ServiceClient, lookup
        from rostool.interfaces.sources import Interfaces
        from rostool.interfaces.srv import load_service

        srv = load_service(Interfaces([tmp_path / "catkin_ws"]), "sum_two_numbers/SumTwoInts")
        uri = lookup(MasterClient(env["ROS_MASTER_URI"], "/test"), "/our_sum")
        with ServiceClient("/our_sum", uri, srv, "/test", persistent=True, timeout=5) as client:
            sums = [client.call(srv.request.message_class()(a=i, b=i)).sum for i in range(20)]
        assert sums == [2 * i for i in range(20)]
    finally:
        stop(ours)
    assert wait_until(lambda: "/our_sum" not in rostool(["service", "list"], env).stdout.split(), 10)
