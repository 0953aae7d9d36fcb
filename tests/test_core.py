"""`rostool core`: the embedded ROS 1 master and parameter server, checked against real ROS 1 peers.

Debian's rospy nodes and command-line tools (rostopic, rosparam, rosnode, rosservice) talk to our
master; Debian's rosmaster answers the same calls for the parity checks.
"""

from __future__ import annotations

import json
import signal
import socket
import threading
import time
import uuid
import xmlrpc.client
from collections.abc import Iterator
from functools import partial
from pathlib import Path
from typing import Any
from xmlrpc.server import SimpleXMLRPCServer

import pytest
import yaml

from rostool.errors import RostoolError
from rostool.graph.ros1.master import Master
from tests.support import (
    debian,
    free_port,
    master_answers,
    require_ros1_peers,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
    wait_until,
)

# ---------------------------------------------------------------------------------------------- helpers


def rpc(uri: str) -> Any:
    """An XML-RPC proxy; replies are checked by value, so they are typed loosely."""
    return xmlrpc.client.ServerProxy(uri)


def master(env: dict[str, str]) -> Any:
    return rpc(env["ROS_MASTER_URI"])


def system_state(env: dict[str, str]) -> dict[str, dict[str, list[str]]]:
    code, _msg, (pubs, subs, srvs) = master(env).getSystemState("/test")
    assert code == 1
    return {
        "publishers": {topic: nodes for topic, nodes in pubs},
        "subscribers": {topic: nodes for topic, nodes in subs},
        "services": {name: nodes for name, nodes in srvs},
    }


def read_when(path: Path, predicate: Any = bool, timeout: float = 20) -> str:
    """The file's text once `predicate(text)` holds (or whatever is there at the timeout)."""
    wait_until(lambda: path.exists() and predicate(path.read_text()), timeout)
    return path.read_text() if path.exists() else ""


class Recorder:
    """A tiny node-side XML-RPC server that records the master's callbacks."""

    def __init__(self) -> None:
        self.calls: list[list[Any]] = []
        self.server = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
        for name in ("paramUpdate", "publisherUpdate", "shutdown"):
            self.server.register_function(self._recorder(name), name)
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}/"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def _recorder(self, name: str) -> Any:
        def record(*args: Any) -> list[Any]:
            self.calls.append([name, *args])
            return [1, "", 0]

        return record

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture
def recorders() -> Iterator[list[Recorder]]:
    made = [Recorder() for _ in range(3)]
    yield made
    for recorder in made:
        recorder.close()


@pytest.fixture
def in_process_master() -> Iterator[Master]:
    with Master(port=0) as running:
        yield running


PUBLISHER = """
import rospy
from std_msgs.msg import String
rospy.init_node("{node}")
pub = rospy.Publisher("{topic}", String, queue_size=10)
rate = rospy.Rate(5)
count = 0
try:
    while not rospy.is_shutdown():
        pub.publish(String(data="{prefix}%d" % count))
        count += 1
        rate.sleep()
except rospy.ROSInterruptException:
    pass
"""

SUBSCRIBER = """
import rospy
from std_msgs.msg import String
out = open({out!r}, "a")
def heard(msg):
    out.write(msg.data + "\\n")
    out.flush()
rospy.init_node("early_listener")
rospy.Subscriber("/chatter", String, heard)
rospy.spin()
"""

TWIN = """
import rospy
rospy.init_node("twin")
open({out!r}, "w").write(rospy.get_node_uri())
rospy.spin()
print("twin exited cleanly", flush=True)
"""

SERVICE = """
import rospy
from roscpp.srv import Empty, EmptyResponse
def handle(request):
    with open({out!r}, "a") as out:
        out.write("called\\n")
    return EmptyResponse()
rospy.init_node("service_node")
rospy.Service("/rostool_test/empty", Empty, handle)
rospy.spin()
"""

PARAM_CLIENT = """
import json, time, rospy
rospy.init_node("searcher")
result = {{
    "node": rospy.get_name(),
    "search_gain": rospy.search_param("gain"),
    "search_missing": rospy.search_param("nothing_here"),
    "cached_initial": rospy.get_param_cached("/watched/value"),
}}
open({ready!r}, "w").write("ready")
deadline = time.time() + 20
while time.time() < deadline and rospy.get_param_cached("/watched/value") == result["cached_initial"]:
    time.sleep(0.05)
result["cached_updated"] = rospy.get_param_cached("/watched/value")
open({out!r}, "w").write(json.dumps(result))
"""


# ------------------------------------------------------------------------------------- topics and nodes


@pytest.mark.ros1
def test_rospy_publisher_seen_by_rosnode_and_rostopic(rostool_master: dict[str, str], tmp_path: Path) -> None:
    require_ros1_peers()
    env = rostool_master
    source = PUBLISHER.format(node="hello_world_pub_node", topic="/hello_world", prefix="Hello_World_")
    node = start_rospy_script(source, env, tmp_path, "hello_pub")
    try:
        assert wait_until(lambda: "/hello_world" in system_state(env)["publishers"], 20)
        assert system_state(env)["publishers"]["/hello_world"] == ["/hello_world_pub_node"]

        nodes = debian(["rosnode", "list"], env)
        assert "/hello_world_pub_node" in nodes.stdout.split(), nodes.stderr

        topics = debian(["rostopic", "list"], env)
        assert "/hello_world" in topics.stdout.split(), topics.stderr

        echo = debian(["rostopic", "echo", "-n", "1", "/hello_world"], env)
        assert 'data: "Hello_World_' in echo.stdout, echo.stderr

        info = debian(["rostopic", "info", "/hello_world"], env)
        assert "Type: std_msgs/String" in info.stdout
        assert " * /hello_world_pub_node (http://127.0.0.1:" in info.stdout, info.stdout

        code, _msg, node_uri = master(env).lookupNode("/test", "/hello_world_pub_node")
        assert code == 1 and node_uri.startswith("http://127.0.0.1:")
        node_info = debian(["rosnode", "info", "/hello_world_pub_node"], env)
        assert (
            node_uri.rstrip("/") in node_info.stdout and "/hello_world [std_msgs/String]" in node_info.stdout
        )

        code, _msg, published = master(env).getPublishedTopics("/test", "")
        assert ["/hello_world", "std_msgs/String"] in published
    finally:
        stop(node)


@pytest.mark.ros1
def test_subscriber_started_first_gets_publisher_update(
    rostool_master: dict[str, str], tmp_path: Path
) -> None:
    require_ros1_peers()
    env = rostool_master
    heard = tmp_path / "heard.txt"
    listener = start_rospy_script(SUBSCRIBER.format(out=str(heard)), env, tmp_path, "listener")
    talker = None
    try:
        assert wait_until(lambda: "/chatter" in system_state(env)["subscribers"], 20)
        assert system_state(env)["subscribers"]["/chatter"] == ["/early_listener"]
        assert "/chatter" not in system_state(env)["publishers"]

        source = PUBLISHER.format(node="late_talker", topic="/chatter", prefix="tick ")
        talker = start_rospy_script(source, env, tmp_path, "talker")
        text = read_when(heard, lambda t: t.count("tick ") >= 2)
        assert text.count("tick ") >= 2, f"listener heard nothing; talker: {stop(talker)}"
        assert all(line.startswith("tick ") for line in text.splitlines())

        # The publisher going away is announced too: the listener's connection list empties.
        stop(talker)
        assert wait_until(lambda: "/chatter" not in system_state(env)["publishers"])
    finally:
        if talker is not None:
            stop(talker)
        stop(listener)


@pytest.mark.ros1
def test_same_name_registration_shuts_old_node_down(rostool_master: dict[str, str], tmp_path: Path) -> None:
    require_ros1_peers()
    env = rostool_master
    first_uri, second_uri = tmp_path / "first.uri", tmp_path / "second.uri"
    first = start_rospy_script(TWIN.format(out=str(first_uri)), env, tmp_path, "twin_first")
    second = None
    try:
        assert read_when(first_uri), stop(first)
        assert wait_until(lambda: master(env).lookupNode("/test", "/twin")[2] == first_uri.read_text(), 20)

        second = start_rospy_script(TWIN.format(out=str(second_uri)), env, tmp_path, "twin_second")
        assert read_when(second_uri), stop(second)
        assert wait_until(lambda: first.poll() is not None, 20), "the old /twin kept running"
        out, _err = first.communicate()
        assert "new node registered with same name" in out
        assert "twin exited cleanly" in out

        assert second.poll() is None
        assert master(env).lookupNode("/test", "/twin")[2] == second_uri.read_text()
        assert debian(["rosnode", "list"], env).stdout.split().count("/twin") == 1
    finally:
        if second is not None:
            stop(second)
        stop(first)


# ------------------------------------------------------------------------------------------- services


@pytest.mark.ros1
def test_rospy_service_listed_and_called(rostool_master: dict[str, str], tmp_path: Path) -> None:
    require_ros1_peers()
    env = rostool_master
    calls = tmp_path / "calls.txt"
    server = start_rospy_script(SERVICE.format(out=str(calls)), env, tmp_path, "service_node")
    try:
        assert wait_until(lambda: "/rostool_test/empty" in system_state(env)["services"], 20)

        listed = debian(["rosservice", "list"], env).stdout.split()
        assert "/rostool_test/empty" in listed
        assert "/service_node/get_loggers" in listed

        info = debian(["rosservice", "info", "/rostool_test/empty"], env)
        assert "Node: /service_node" in info.stdout and "Type: roscpp/Empty" in info.stdout

        code, _msg, service_uri = master(env).lookupService("/test", "/rostool_test/empty")
        assert code == 1 and service_uri.startswith("rosrpc://127.0.0.1:")
        assert debian(["rosservice", "uri", "/rostool_test/empty"], env).stdout.strip() == service_uri

        called = debian(["rosservice", "call", "/rostool_test/empty"], env)
        assert called.returncode == 0, called.stderr
        assert read_when(calls) == "called\n"

        loggers = debian(["rosservice", "call", "/service_node/get_loggers"], env)
        assert "loggers:" in loggers.stdout and "level:" in loggers.stdout, loggers.stderr
    finally:
        stop(server)
    assert wait_until(lambda: "/rostool_test/empty" not in system_state(env)["services"])
    assert master(env).lookupService("/test", "/rostool_test/empty") == [-1, "no provider", ""]


# ----------------------------------------------------------------------------------------- parameters

PARAM_VALUES: dict[str, tuple[str, Any]] = {
    "int": ("42", 42),
    "negative": ("-7", -7),
    "float": ("3.25", 3.25),
    "bool": ("true", True),
    "string": ("hello world", "hello world"),
    "list": ("[1, 2.5, three, false]", [1, 2.5, "three", False]),
    "dict": ("{a: 1, b: {c: [x, y]}}", {"a": 1, "b": {"c": ["x", "y"]}}),
}


@pytest.mark.ros1
def test_rosparam_round_trip_every_yaml_type(rostool_master: dict[str, str], tmp_path: Path) -> None:
    require_ros1_peers()
    env = rostool_master
    expected = {name: value for name, (_text, value) in PARAM_VALUES.items()}
    for name, (text, value) in PARAM_VALUES.items():
        result = debian(["rosparam", "set", f"/t/{name}", text], env)
        assert result.returncode == 0, result.stderr
        code, _msg, stored = master(env).getParam("/test", f"/t/{name}")
        assert code == 1 and stored == value and type(stored) is type(value)
        got = debian(["rosparam", "get", f"/t/{name}"], env)
        assert yaml.safe_load(got.stdout) == value

    assert yaml.safe_load(debian(["rosparam", "get", "/t"], env).stdout) == expected
    listed = debian(["rosparam", "list", "/t"], env).stdout.split()
    assert sorted(listed) == sorted(
        ["/t/int", "/t/negative", "/t/float", "/t/bool", "/t/string", "/t/list", "/t/dict/a", "/t/dict/b/c"]
    )
    assert {"/rosdistro", "/rosversion", "/run_id"} <= set(debian(["rosparam", "list"], env).stdout.split())

    dump = tmp_path / "dump.yaml"
    assert debian(["rosparam", "dump", str(dump), "/t"], env).returncode == 0
    assert yaml.safe_load(dump.read_text()) == expected
    loaded = debian(["rosparam", "load", str(dump), "/copy"], env)
    assert loaded.returncode == 0, loaded.stderr
    assert master(env).getParam("/test", "/copy")[2] == expected

    # rosparam merges a dict into the namespace key by key; a dict sent in one setParam replaces it.
    assert debian(["rosparam", "set", "/copy", "{only: 1}"], env).returncode == 0
    assert master(env).getParam("/test", "/copy")[2] == {**expected, "only": 1}
    assert master(env).setParam("/test", "/copy", {"only": 1}) == [1, "parameter /copy set", 0]
    assert yaml.safe_load(debian(["rosparam", "get", "/copy"], env).stdout) == {"only": 1}

    assert debian(["rosparam", "delete", "/t/int"], env).returncode == 0
    assert master(env).getParam("/test", "/t/int") == [-1, "Parameter [/t/int] is not set", 0]
    missing = debian(["rosparam", "get", "/t/int"], env)
    assert missing.returncode != 0 and "/t/int" in missing.stderr
    assert "/t/int" not in master(env).getParamNames("/test")[2]


@pytest.mark.ros1
def test_core_params_follow_roscore(debian_roscore: dict[str, str], tmp_path: Path) -> None:
    theirs = {key: master(debian_roscore).getParam("/test", key)[2] for key in ("/rosdistro", "/rosversion")}
    their_get = debian(["rosparam", "get", "/rosdistro"], debian_roscore).stdout
    their_run_id = master(debian_roscore).getParam("/test", "/run_id")[2]
    assert uuid.UUID(their_run_id).version == 1

    # roscore stores `rosversion -d` output, trailing newline included; that prints $ROS_DISTRO when set.
    port = free_port()
    distro = theirs["/rosdistro"].strip()
    env = {**debian_roscore, "ROS_MASTER_URI": f"http://127.0.0.1:{port}", "ROS_DISTRO": distro}
    ours = rostool_popen(["core", "--port", str(port)], env)
    try:
        assert wait_until(lambda: master_answers(env["ROS_MASTER_URI"]), 20), stop(ours)
        assert master(env).getParam("/test", "/rosdistro")[2] == theirs["/rosdistro"]
        assert debian(["rosparam", "get", "/rosdistro"], env).stdout == their_get
        our_version = master(env).getParam("/test", "/rosversion")[2]
        assert our_version.endswith("\n") and theirs["/rosversion"].endswith("\n")
        assert [part.isdigit() for part in our_version.strip().split(".")] == [True, True, True]
        assert uuid.UUID(master(env).getParam("/test", "/run_id")[2]).version == 1
    finally:
        stop(ours)


def test_default_distro_is_noetic(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("ROS_DISTRO", raising=False)
    with Master(port=0) as running:
        proxy = rpc(running.uri)
        assert proxy.getParam("/test", "/rosdistro") == [1, "Parameter [/rosdistro]", "noetic\n"]
        assert proxy.getParam("/test", "/rosversion") == [1, "Parameter [/rosversion]", "1.16.0\n"]
        assert uuid.UUID(proxy.getParam("/test", "/run_id")[2]).version == 1
        assert sorted(proxy.getParamNames("/test")[2]) == ["/rosdistro", "/rosversion", "/run_id"]


@pytest.mark.ros1
def test_rospy_search_param_and_cached_param_updates(rostool_master: dict[str, str], tmp_path: Path) -> None:
    require_ros1_peers()
    env = {**rostool_master, "ROS_NAMESPACE": "/robot/arm"}
    proxy = master(env)
    proxy.setParam("/test", "/robot/gain", 2.5)
    proxy.setParam("/test", "/gain", 1.0)
    proxy.setParam("/test", "/watched/value", 1)
    ready, out = tmp_path / "ready", tmp_path / "result.json"
    client = start_rospy_script(PARAM_CLIENT.format(ready=str(ready), out=str(out)), env, tmp_path, "params")
    try:
        assert read_when(ready), stop(client)
        assert debian(["rosparam", "set", "/watched/value", "2"], rostool_master).returncode == 0
        result = json.loads(read_when(out) or "{}")
    finally:
        stop(client)
    assert result == {
        "node": "/robot/arm/searcher",
        "search_gain": "/robot/gain",
        "search_missing": None,
        "cached_initial": 1,
        "cached_updated": 2,
    }


@pytest.mark.ros1
def test_param_updates_reach_subscribers_and_dead_ones_do_not_block(
    rostool_master: dict[str, str], recorders: list[Recorder]
) -> None:
    require_ros1_peers()
    env = rostool_master
    proxy = master(env)
    live = recorders[0]
    hung = socket.socket()  # accepts connections, never answers
    hung.bind(("127.0.0.1", 0))
    hung.listen(16)
    dead_uri = f"http://127.0.0.1:{free_port()}/"
    try:
        for caller_id, uri in (("/hung", f"http://127.0.0.1:{hung.getsockname()[1]}/"), ("/dead", dead_uri)):
            assert proxy.subscribeParam(caller_id, uri, "/watched")[0] == 1
        assert proxy.subscribeParam("/live", live.uri, "/watched") == [
            1,
            "Subscribed to parameter [/watched]",
            {},
        ]

        steps: list[tuple[Any, list[Any]]] = [
            (["rosparam", "set", "/watched/x", "1"], ["paramUpdate", "/master", "/watched/x/", 1]),
            # rosparam sets a dict key by key
            (["rosparam", "set", "/watched", "{a: 1}"], ["paramUpdate", "/master", "/watched/a/", 1]),
            (("/other", "/watched", {"b": [2]}), ["paramUpdate", "/master", "/watched/", {"b": [2]}]),
            (["rosparam", "delete", "/watched"], ["paramUpdate", "/master", "/watched/", {}]),
        ]
        for command, update in steps:
            if isinstance(command, list):
                assert debian(command, env, timeout=10).returncode == 0
            else:
                assert proxy.setParam(*command)[0] == 1
            assert wait_until(partial(list.__contains__, live.calls, update)), live.calls
        assert [call[2] for call in live.calls] == ["/watched/x/", "/watched/a/", "/watched/", "/watched/"]

        # The setter itself is not told about its own change.
        proxy.setParam("/live", "/watched/own", 5)
        proxy.setParam("/other", "/watched/theirs", 6)
        assert wait_until(lambda: ["paramUpdate", "/master", "/watched/theirs/", 6] in live.calls)
        assert ["paramUpdate", "/master", "/watched/own/", 5] not in live.calls

        assert proxy.unsubscribeParam("/live", live.uri, "/watched") == [
            1,
            "Unsubscribe to parameter [/watched]",
            1,
        ]
        proxy.setParam("/other", "/watched/after", 7)
        assert proxy.getParam("/x", "/watched") == [
            1,
            "Parameter [/watched]",
            {"own": 5, "theirs": 6, "after": 7},
        ]
    finally:
        hung.close()


# ------------------------------------------------------------------------------------------ lifecycle


def test_port_in_use_is_one_clear_line(rostool_master: dict[str, str]) -> None:
    port = rostool_master["ROS_MASTER_URI"].rsplit(":", 1)[1]
    result = rostool(["core", "--port", port], rostool_master, timeout=20)
    assert result.returncode != 0
    assert result.stderr.strip().splitlines() == [
        f"rostool: port {port} is in use on 127.0.0.1: another master is probably running; "
        "pick another with --port"
    ]
    assert "Traceback" not in result.stderr + result.stdout
    assert master_answers(rostool_master["ROS_MASTER_URI"])


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_stops_core_cleanly(ros_env: dict[str, str], sig: signal.Signals) -> None:
    port = ros_env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = rostool_popen(["core", "--port", port], ros_env)
    try:
        assert wait_until(lambda: master_answers(ros_env["ROS_MASTER_URI"]), 20)
        assert master(ros_env).getUri("/test") == [1, "", f"http://127.0.0.1:{port}/"]
        assert master(ros_env).setParam("/test", "/x", 1) == [1, "parameter /x set", 0]
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=10)
    finally:
        stop(proc)
    assert proc.returncode == 0, err
    # The banner and nothing else: no per-request log, no traceback.
    assert err.splitlines() == [f"started rostool core at http://127.0.0.1:{port}/ (ROS_MASTER_URI)"]
    assert out == ""
    assert not master_answers(ros_env["ROS_MASTER_URI"])


def test_shutdown_call_stops_core(ros_env: dict[str, str]) -> None:
    port = ros_env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = rostool_popen(["core", "--port", port], ros_env)
    try:
        assert wait_until(lambda: master_answers(ros_env["ROS_MASTER_URI"]), 20)
        assert master(ros_env).shutdown("/admin", "maintenance") == [1, "shutdown", 0]
        _out, err = proc.communicate(timeout=10)
    finally:
        stop(proc)
    assert proc.returncode == 0
    assert "shutdown request from [/admin]: maintenance" in err


def test_help_has_an_example(ros_env: dict[str, str]) -> None:
    result = rostool(["core", "--help"], ros_env)
    assert result.returncode == 0
    assert "Examples:" in result.stdout and "rostool core --port" in result.stdout


def test_library_master_reports_port_in_use(in_process_master: Master) -> None:
    with pytest.raises(RostoolError, match=f"port {in_process_master.port} is in use on 127.0.0.1"):
        Master(port=in_process_master.port).start()


# ----------------------------------------------------------------------------- parity with rosmaster

U1, U2, U3 = "http://127.0.0.1:1/", "http://127.0.0.1:2/", "http://127.0.0.1:3/"
PARITY_CALLS: list[tuple[Any, ...]] = [
    ("setParam", "/ns/node", "a", 1),
    ("setParam", "/ns/node", "~priv", "x"),
    ("setParam", "/ns/node", "/g/d", {"x": 1, "y": {"z": [1, 2.5, "s", True]}}),
    ("getParam", "/ns/node", "a"),
    ("getParam", "/ns/node", "/ns/node/priv"),
    ("getParam", "/ns/node", "/g"),
    ("getParam", "/ns/node", "/g/d/y/z"),
    ("getParam", "/ns/node", "/nope"),
    ("getParam", "/ns/node", ""),
    ("getParam", "/ns/node", 5),
    ("getParam", "/ns/node"),
    ("getParam", 7, "x"),
    ("setParam", "/x", "/", 5),
    ("setParam", "/x", "/g/d/x/deeper", 3),
    ("getParam", "/x", "/g"),
    ("hasParam", "/ns/node", "~priv"),
    ("hasParam", "/ns/node", "/zz"),
    ("getParamNames", "/n"),
    ("searchParam", "/ns/node", "a"),
    ("searchParam", "/ns/other/deep/node", "a/b/c"),
    ("searchParam", "/ns/node", "priv"),
    ("searchParam", "/ns/node", "/g/nope"),
    ("searchParam", "/ns/node", "~priv"),
    ("searchParam", "relative", "a"),
    ("searchParam", "/ns/node", "zzz"),
    ("deleteParam", "/ns/node", "/g/d/y"),
    ("deleteParam", "/ns/node", "/g/d/y"),
    ("deleteParam", "/ns/node", "/"),
    ("getParam", "/x", "/"),
    ("registerPublisher", "/pub", "chatter", "std_msgs/String", U1),
    ("registerPublisher", "/pub", "/other", "*", U1),
    ("registerPublisher", "/pub", "/other", "std_msgs/Int32", U1),
    ("registerPublisher", "/pub", "/other", "*", U1),
    ("registerPublisher", "/pub", "/bad", "bad", U1),
    ("registerPublisher", "/pub", "/bad:x", "a/b", U1),
    ("registerPublisher", "/pub", "/", "a/b", U1),
    ("registerPublisher", "/pub", "/t", "a/b", "ftp://x"),
    ("registerSubscriber", "/a/sub", "chatter", "std_msgs/String", U2),
    ("registerSubscriber", "/a/sub", "~priv_topic", "*", U2),
    ("registerSubscriber", "/a/sub", "/typed_by_sub", "pkg/T", U2),
    ("getSystemState", "/x"),
    ("getTopicTypes", "/x"),
    ("getPublishedTopics", "/x", ""),
    ("getPublishedTopics", "/x", "/oth"),
    ("getPublishedTopics", "/x", "/other"),
    ("lookupNode", "/x", "pub"),
    ("lookupNode", "/x", "/nobody"),
    ("registerService", "/srv_node", "svc", "rosrpc://127.0.0.1:5/", U3),
    ("lookupService", "/x", "/svc"),
    ("lookupService", "/x", "/nosvc"),
    ("unregisterService", "/srv_node", "/svc", "rosrpc://127.0.0.1:9/"),
    ("unregisterService", "/other_node", "/svc", "rosrpc://127.0.0.1:5/"),
    ("unregisterService", "/srv_node", "/svc", "rosrpc://127.0.0.1:5/"),
    ("unregisterPublisher", "/pub", "/chatter", "http://127.0.0.1:9/"),
    ("unregisterPublisher", "/nobody", "/chatter", U1),
    ("unregisterPublisher", "/pub", "/chatter", U1),
    ("unregisterSubscriber", "/a/sub", "/chatter", U2),
    ("getSystemState", "/x"),
    ("subscribeParam", "/p", U3, "/g"),
    ("subscribeParam", "/p", "nope", "unset"),
    ("unsubscribeParam", "/p", U3, "unset"),
    ("registerPublisher", "/pub", "/other", "std_msgs/Int32", "http://127.0.0.1:11/"),
    ("getSystemState", "/x"),
    ("lookupNode", "/x", "/pub"),
    ("getUri", "/x", "extra"),
    ("shutdown",),
]


def _replies(uri: str) -> list[Any]:
    proxy = rpc(uri)
    replies: list[Any] = []
    for method, *args in PARITY_CALLS:
        replies.append(getattr(proxy, method)(*args))
    try:
        proxy.noSuchMethod("/x")
    except xmlrpc.client.Fault as fault:
        replies.append(fault.faultString)
    batch = xmlrpc.client.MultiCall(proxy)
    batch.getParam("/x", "/g")
    batch.hasParam("/x", "nope")
    replies.append(list(batch().results))
    return replies


@pytest.mark.ros1
def test_replies_match_rosmaster(debian_master: dict[str, str]) -> None:
    theirs = _replies(debian_master["ROS_MASTER_URI"])
    with Master(port=0, set_core_params=False) as ours:
        mine = _replies(ours.uri)
    assert len(mine) == len(theirs)
    for call, their_reply, our_reply in zip(PARITY_CALLS, theirs, mine, strict=False):
        assert our_reply == their_reply, call
    assert mine[len(PARITY_CALLS) :] == theirs[len(PARITY_CALLS) :]


NOTIFY_STEPS: list[tuple[Any, ...]] = [
    ("subscribeParam", "/watcher", "R0", "/w"),
    ("subscribeParam", "/watcher2", "R1", "/w/a/b"),
    ("subscribeParam", "/watcher3", "R2", "/"),
    ("setParam", "/setter", "/w/a/b", 1),
    ("setParam", "/watcher", "/w/x", 2),
    ("setParam", "/setter", "/w", {"a": {"b": {"deep": 3}}, "c": 4}),
    ("setParam", "/setter", "/w", {"c": 5}),
    ("setParam", "/setter", "/w/a", {"b": 7}),
    ("deleteParam", "/setter", "/w/a"),
    ("deleteParam", "/setter", "/w"),
    ("registerSubscriber", "/sub1", "/t", "std_msgs/String", "R0"),
    ("registerPublisher", "/pub1", "/t", "std_msgs/String", U1),
    ("registerPublisher", "/pub2", "/t", "std_msgs/String", U2),
    ("unregisterPublisher", "/pub1", "/t", U1),
    ("registerSubscriber", "/twin", "/t2", "std_msgs/String", "R1"),
    ("registerSubscriber", "/twin", "/t3", "std_msgs/String", "R2"),
]


def _callbacks(uri: str, recorders: list[Recorder], settled: Any) -> list[list[list[Any]]]:
    proxy = rpc(uri)
    by_name = {f"R{i}": recorder.uri for i, recorder in enumerate(recorders)}
    for method, *args in NOTIFY_STEPS:
        args = [by_name.get(arg, arg) if isinstance(arg, str) else arg for arg in args]
        assert getattr(proxy, method)(*args)[0] == 1
        settled()
    return [recorder.calls for recorder in recorders]


@pytest.mark.ros1
def test_callbacks_match_rosmaster(debian_master: dict[str, str]) -> None:
    first, second = [Recorder() for _ in range(3)], [Recorder() for _ in range(3)]
    try:
        theirs = _callbacks(debian_master["ROS_MASTER_URI"], first, lambda: time.sleep(0.5))
        with Master(port=0, set_core_params=False) as ours:
            mine = _callbacks(ours.uri, second, lambda: wait_until(lambda: not ours.api.notifier.busy()))
    finally:
        for recorder in first + second:
            recorder.close()
    assert mine == theirs
    assert ["shutdown", "/master", "[/twin] Reason: new node registered with same name"] in mine[1]
    assert ["publisherUpdate", "/master", "/t", [U1, U2]] in mine[0]


# ------------------------------------------------------------------------------ in-process behaviour


def test_many_concurrent_clients(in_process_master: Master) -> None:
    errors: list[str] = []

    def client(index: int) -> None:
        proxy = rpc(in_process_master.uri)
        caller, api = f"/client_{index}", f"http://127.0.0.1:{20000 + index}/"
        for step in range(20):
            replies = [
                proxy.registerPublisher(caller, f"/topic_{step % 4}", "std_msgs/String", api),
                proxy.setParam(caller, f"~value_{step}", step),
                proxy.getParam(caller, f"~value_{step}"),
                proxy.getSystemState(caller),
            ]
            if [reply[0] for reply in replies] != [1, 1, 1, 1] or replies[2][2] != step:
                errors.append(f"{caller}: {replies}")

    threads = [threading.Thread(target=client, args=(i,)) for i in range(32)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert not errors, errors[:3]
    proxy = rpc(in_process_master.uri)
    publishers = dict(proxy.getSystemState("/x")[2][0])
    assert {topic: len(nodes) for topic, nodes in publishers.items()} == {f"/topic_{i}": 32 for i in range(4)}
    assert len([name for name in proxy.getParamNames("/x")[2] if name.startswith("/client_")]) == 32 * 20


def test_hung_subscriber_does_not_block_registration(
    in_process_master: Master, recorders: list[Recorder]
) -> None:
    hung = socket.socket()
    hung.bind(("127.0.0.1", 0))
    hung.listen(16)
    try:
        proxy = rpc(in_process_master.uri)
        hung_uri = f"http://127.0.0.1:{hung.getsockname()[1]}/"
        assert proxy.registerSubscriber("/stuck", "/t", "std_msgs/String", hung_uri)[0] == 1
        assert proxy.registerSubscriber("/fine", "/t", "std_msgs/String", recorders[0].uri)[0] == 1
        for index in range(5):
            reply = proxy.registerPublisher(
                f"/pub_{index}", "/t", "std_msgs/String", f"http://127.0.0.1:{index + 1}/"
            )
            assert reply[0] == 1
        # The healthy subscriber ends with the full publisher list while the hung one still blocks.
        final = ["publisherUpdate", "/master", "/t", [f"http://127.0.0.1:{i + 1}/" for i in range(5)]]
        assert wait_until(lambda: bool(recorders[0].calls) and recorders[0].calls[-1] == final)
        assert in_process_master.api.notifier.busy()
    finally:
        hung.close()
