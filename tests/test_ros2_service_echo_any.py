"""`rostool --ros2 service echo` of any service type, against real rclpy servers with introspection on.

The peers: /set_flag_node serves std_srvs/srv/SetBool on /set_flag and calls it every 0.5 s (data True,
False, True, ...: the call with sequence number N sends N odd), /basic_node serves test_msgs/srv/BasicTypes
on /basic (echoing the request) and calls it with {bool_value: true, int32_value: 42, string_value:
test_string_value}, both with introspection CONTENTS on server and client. rostool runs without any
interface sources (no AMENT_PREFIX_PATH): neither event type is in its built-in store, so the DDS backend
learns it from the service's node (its type description), the rclpy backend from the class rclpy imports.

The referee is the real `ros2 service echo` (ros2cli Jazzy, tests/parity_ros2cli.py): the same events, text
for text, once stamps, client GIDs and sequence numbers (which differ from run to run) are zeroed.
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.parity_ros2cli import ROS2, require_ros2cli
from tests.ros2_backends import ServedTool, Tool
from tests.ros2_peers import PEERS_DIR, StartPeer, peer_env, rclpy_command

EVENT_TYPES = ("REQUEST_SENT", "REQUEST_RECEIVED", "RESPONSE_SENT", "RESPONSE_RECEIVED")
REQUESTS = ("REQUEST_SENT", "REQUEST_RECEIVED")
SET_BOOL_PEER = ("--name", "set_flag_node", "--setbool-introspect", "/set_flag")
BASIC_PEER = ("--name", "basic_node", "--echo-service", "/basic", "--introspect")
# what /basic_node's client sends (tests/rclpy_peer.py's call_echo), every other field at its default
BASIC_CALL = {"bool_value": True, "int32_value": 42, "string_value": "test_string_value"}
BASIC_FIELDS = ("bool_value", "byte_value", "char_value", "float32_value", "float64_value", "int8_value",
                "uint8_value", "int16_value", "uint16_value", "int32_value", "uint32_value", "int64_value",
                "uint64_value", "string_value")  # fmt: skip


@pytest.fixture
def no_sources(graph_env: dict[str, str]) -> dict[str, str]:
    """The test's graph without interface sources: event types must come from the graph itself."""
    for name in ("AMENT_PREFIX_PATH", "ROSTOOL_INTERFACES", "ROS_PACKAGE_PATH"):
        graph_env.pop(name, None)
    return graph_env


@pytest.fixture(params=["no_sources", "sources"])
def daemon_sources(request: pytest.FixtureRequest, no_sources: dict[str, str], distro: str) -> dict[str, str]:
    """The graph without interface sources, or with the distro's (AMENT_PREFIX_PATH, as a sourced ROS 2
    gives them): set before the graph daemon starts with it."""
    if request.param == "sources":
        no_sources["AMENT_PREFIX_PATH"] = str(PEERS_DIR / distro)
    return no_sources


def events(stdout: str) -> list[dict[str, Any]]:
    """The events of echo's YAML output, each block up to its `---` line."""
    blocks = re.split(r"^---$", stdout, flags=re.MULTILINE)
    return [yaml.safe_load(block) for block in blocks if block.strip()]


def check_set_bool(found: list[dict[str, Any]]) -> None:
    """SetBool events: the request's data in REQUEST_*, the server's answer in RESPONSE_*, and what every
    call carries (data odd sequence number, success equal to it, message "flag is ...")."""
    assert {event["info"]["event_type"] for event in found} == set(EVENT_TYPES), found
    for event in found:
        info = event["info"]
        assert list(event) == ["info", "request", "response"]
        assert list(info) == ["event_type", "stamp", "client_gid", "sequence_number"]
        assert info["stamp"]["sec"] > 0 and 0 <= info["stamp"]["nanosec"] < 10**9
        assert len(info["client_gid"]) == 16 and all(0 <= b <= 255 for b in info["client_gid"])
        data = info["sequence_number"] % 2 == 1
        if info["event_type"] in REQUESTS:
            assert event["request"] == [{"data": data}] and event["response"] == [], event
        else:
            answer = {"success": data, "message": f"flag is {data}"}
            assert event["request"] == [] and event["response"] == [answer], event


def check_basic_types(found: list[dict[str, Any]]) -> None:
    """BasicTypes events: every field of the request (echoed back as the response) in .srv order."""
    assert {event["info"]["event_type"] for event in found} == set(EVENT_TYPES), found
    for event in found:
        is_request = event["info"]["event_type"] in REQUESTS
        side, empty = ("request", "response") if is_request else ("response", "request")
        assert event[empty] == [] and len(event[side]) == 1, event
        (sent,) = event[side]
        assert tuple(sent) == BASIC_FIELDS, sent
        assert {name: sent[name] for name in BASIC_CALL} == BASIC_CALL
        defaults = [name for name in BASIC_FIELDS if name not in BASIC_CALL and name != "byte_value"]
        assert all(sent[name] == 0 for name in defaults), sent


def test_set_bool_events(tool: Tool, start_peer: StartPeer, no_sources: dict[str, str]) -> None:
    """std_srvs/srv/SetBool (rostool has its .srv text for `service call`, but no event type): all four
    events of each call, with the request's data and the server's answer."""
    peer = start_peer(*SET_BOOL_PEER)
    done = tool(["service", "echo", "/set_flag", "-n", "8", "--timeout", "20"])
    assert done.returncode == 0 and not done.stderr_lines, done  # type: ignore[attr-defined]
    found = events(done.stdout)
    assert len(found) == 8
    check_set_bool(found)
    assert peer.of("service"), "the peer's server answered no call"


def test_any_type_events(tool: Tool, start_peer: StartPeer, no_sources: dict[str, str]) -> None:
    """test_msgs/srv/BasicTypes: a type in neither rosbags' store nor rostool's built-in services."""
    from rostool.interfaces.ros2_srv import SRV_DEFINITIONS
    from rostool.interfaces.ros2_types import Ros2Types

    assert not Ros2Types().knows("test_msgs/srv/BasicTypes_Event")
    assert "test_msgs/srv/BasicTypes" not in SRV_DEFINITIONS
    start_peer(*BASIC_PEER)
    done = tool(["service", "echo", "/basic", "-n", "8", "--timeout", "20"])
    assert done.returncode == 0 and not done.stderr_lines, done  # type: ignore[attr-defined]
    found = events(done.stdout)
    assert len(found) == 8
    check_basic_types(found)


def test_events_through_graph_daemon(
    daemon_sources: dict[str, str], served_tool: ServedTool, start_peer: StartPeer
) -> None:
    """Relayed by the graph daemon (a user's default): the daemon learned the event type (from its node, or
    built it from the sources), and its TYPE frame carries it to the verb. rosbags writes no .msg text for a
    `pkg/srv/` type, so the frame carried none and the verb failed with sources ("cannot decode a
    std_srvs/srv/SetBool_Event message on /set_flag/_service_event: 'std_srvs/srv/SetBool_Event'")."""
    start_peer.together(list(SET_BOOL_PEER), list(BASIC_PEER))
    served_tool.daemon.ready()
    for service, check in (("/set_flag", check_set_bool), ("/basic", check_basic_types)):
        done = served_tool(["service", "echo", service, "-n", "8", "--timeout", "20"])
        assert done.returncode == 0 and not done.stderr_lines, done  # type: ignore[attr-defined]
        check(events(done.stdout))


# --- the real ros2 service echo as referee --------------------------------------------------------------

_ZEROED = [
    (re.compile(r"^(\s*(?:sec|nanosec|sequence_number): )\d+$", re.MULTILINE), r"\g<1>0"),
    (re.compile(r"^  - \d+$", re.MULTILINE), "  - 0"),  # client_gid's bytes, block style
    (re.compile(r"client_gid: \[[\d, ]+\]"), "client_gid: [0]"),  # flow style
]
_CSV_ROW = re.compile(r"^(\d),\d+,\d+,(?:\d+,){16}\d+,", re.MULTILINE)  # event type, stamp, GID, number


def zeroed_events(stdout: str, flags: tuple[str, ...]) -> set[str]:
    """The distinct events printed, with what differs between runs zeroed: the text of each, except under
    --flow-style, where rostool prints the flow style asked for and ros2 block mappings around flow lists
    (a deliberate difference, see test_ros2cli_parity.py's DELIBERATE): there the values, in field order."""
    if "--csv" in flags:
        return {_CSV_ROW.sub(r"\g<1>,0,0,GID,0,", line) for line in stdout.splitlines() if line}
    if "--flow-style" in flags:
        return {json.dumps(_zeroed(event)) for event in events(stdout)}
    for pattern, replacement in _ZEROED:
        stdout = pattern.sub(replacement, stdout)
    return {block.strip("\n") for block in re.split(r"^---$", stdout, flags=re.MULTILINE) if block.strip()}


def _zeroed(event: dict[str, Any]) -> dict[str, Any]:
    info = dict(event["info"], stamp={"sec": 0, "nanosec": 0}, sequence_number=0)
    info["client_gid"] = [0] * len(info["client_gid"]) if isinstance(info["client_gid"], list) else "GID"
    return dict(event, info=info)


def ros2_echo(args: list[str], env: dict[str, str], seconds: float) -> str:
    """`ros2 service echo ARGS` for `seconds` (it runs until Ctrl+C), without its line "No publishers on
    topic ...", which it prints when its first spin comes before discovery matched."""
    process = subprocess.Popen([str(ROS2), "service", "echo", *args], env=env, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    try:
        out, err = process.communicate(timeout=seconds)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=15)
    assert "Traceback" not in err, err
    return "".join(line for line in out.splitlines(keepends=True) if not line.startswith("No publishers on"))


def rostool_echo(backend: str, args: list[str], env: dict[str, str], tmp_path: Path) -> str:
    command = [sys.executable, "-m", "rostool", "--ros2", "service", "echo", *args]
    if backend == "rclpy":
        command, env = rclpy_command(["--ros2", "service", "echo", *args], "jazzy"), peer_env(env, tmp_path)
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done
    return done.stdout


# (service, SERVICE_TYPE ros2 is given: its own lookup of the type fails while its daemon is cold, and the
# form's flags); each ends up with every distinct event of its service: 4 kinds, each with data True and
# False for SetBool (unless --no-arr hides it), the one request of /basic_node's client for BasicTypes
FORMS = [
    ("/set_flag", "std_srvs/srv/SetBool", ()),
    ("/set_flag", "std_srvs/srv/SetBool", ("--no-arr",)),
    ("/set_flag", "std_srvs/srv/SetBool", ("--flow-style",)),
    ("/set_flag", "std_srvs/srv/SetBool", ("--csv",)),
    ("/basic", "test_msgs/srv/BasicTypes", ()),
    ("/basic", "test_msgs/srv/BasicTypes", ("--no-str", "--flow-style")),
]


@pytest.mark.parametrize("distro", ["jazzy"])
def test_same_events_as_ros2(start_peer: StartPeer, no_sources: dict[str, str], tmp_path: Path) -> None:
    """Each form of ros2 service echo and rostool's (both backends, with and without SERVICE_TYPE) print
    the same distinct events."""
    require_ros2cli()
    start_peer.together(list(SET_BOOL_PEER), list(BASIC_PEER))
    venv = str(PEERS_DIR / "jazzy")
    # ros2 as a sourced Jazzy user runs it: its interfaces on AMENT_PREFIX_PATH
    path = f"{venv}/bin:{no_sources['PATH']}"
    ros2_env = dict(peer_env(no_sources, tmp_path), AMENT_PREFIX_PATH=venv, PATH=path)
    try:
        for service, srv_type, flags in FORMS:
            limit = ["-n", "20" if service == "/set_flag" else "8", "--timeout", "20"]
            with ThreadPoolExecutor(3) as pool:  # the referee and both backends side by side
                referee = pool.submit(ros2_echo, [service, srv_type, *flags], ros2_env, 8)
                ours = {
                    backend: pool.submit(
                        rostool_echo, backend, [service, *typed, *flags, *limit], no_sources, tmp_path
                    )
                    for backend, typed in (("dds", ()), ("rclpy", (srv_type,)))
                }
                expected = zeroed_events(referee.result(), flags)
                got = {backend: zeroed_events(future.result(), flags) for backend, future in ours.items()}
            varied = service == "/set_flag" and "--no-arr" not in flags  # the data shows: True and False
            assert len(expected) == (8 if varied else 4), (flags, expected)
            for backend, found in got.items():
                assert found == expected, (service, flags, backend, sorted(found ^ expected))
    finally:
        subprocess.run([str(ROS2), "daemon", "stop"], env=ros2_env, capture_output=True, timeout=30)
