"""`rostool node`, `param` and `msg` against Debian's real rosmaster, rospy, rosnode and rosparam."""

from __future__ import annotations

import json
import re
from pathlib import Path

import yaml

from tests.peers import HELLO_PUBLISHER, HELLO_SUBSCRIBER
from tests.support import DEBIAN_PYTHON, debian, rostool, start_rospy_script, stop, wait_until

EVERY_TYPE = {
    "an_int": 42,
    "negative": -7,
    "a_float": 0.05,
    "whole_float": 2.0,
    "yes": True,
    "no": False,
    "text": "hello world",
    "numeric_text": "42",
    "empty_text": "",
    "a_list": [1, 2.5, "three", False],
    "nested": {"inner": {"deep": 1.5, "name": "x"}, "items": [{"a": 1}, {"b": [1, 2]}]},
}


def test_node_list_info_ping_kill(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    pub = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    sub = start_rospy_script(HELLO_SUBSCRIBER, env, tmp_path, "listener")
    try:
        both = {"/hello_world_pub_node", "/hello_world_sub_node"}
        assert wait_until(lambda: both <= set(rostool(["node", "list"], env).stdout.split()), 30)
        names = rostool(["node", "list"], env).stdout.split()
        assert names == debian(["rosnode", "list"], env).stdout.split()
        assert wait_until(
            lambda: "Connections:" in rostool(["node", "info", "/hello_world_pub_node"], env).stdout, 30
        )
        info = rostool(["node", "info", "/hello_world_pub_node"], env).stdout
        theirs = debian(["rosnode", "info", "/hello_world_pub_node"], env).stdout
        assert " * /hello_world [std_msgs/String]" in info
        pid = re.search(r"^Pid: (\d+)$", info, re.M)
        assert pid and pid.group(1) == str(pub.pid)
        assert pid.group(0) in theirs
        # the header part (publications/subscriptions/services) is the same text rosnode prints
        assert info.split("\ncontacting node")[0] == theirs.split("\ncontacting node")[0]
        assert " * topic: /hello_world\n    * to: /hello_world_sub_node\n    * direction: outbound" in info
        data = json.loads(rostool(["node", "info", "/hello_world_pub_node", "--json"], env).stdout)
        assert (
            data["pid"] == pub.pid
            and {"topic": "/hello_world", "type": "std_msgs/String"} in data["publications"]
        )
        ping = rostool(["node", "ping", "/hello_world_pub_node", "-c", "2"], env)
        assert ping.stdout.count("xmlrpc reply from http://127.0.0.1:") == 2
        killed = rostool(["node", "kill", "/hello_world_pub_node"], env)
        assert killed.stdout == "killing /hello_world_pub_node\nkilled\n", killed.stderr
        pub.wait(10)
        assert pub.returncode is not None
    finally:
        stop(pub)
        stop(sub)


def test_rosnode_kill_ends_our_node_cleanly(debian_master: dict[str, str]) -> None:
    from tests.support import rostool_popen

    env = debian_master
    echo = rostool_popen(["topic", "echo", "/anything"], env)
    assert wait_until(
        lambda: any(n.startswith("/rostool") for n in debian(["rosnode", "list"], env).stdout.split())
    )
    ours = next(n for n in debian(["rosnode", "list"], env).stdout.split() if n.startswith("/rostool"))
    debian(["rosnode", "kill", ours], env)
    echo.wait(10)
    assert echo.stderr is not None and "Traceback" not in echo.stderr.read()
    assert ours not in debian(["rosnode", "list"], env).stdout.split()


def test_param_round_trip_with_their_rosparam(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    # ours -> theirs, every YAML type
    for key, value in EVERY_TYPE.items():
        text = yaml.safe_dump(value, default_flow_style=True).removesuffix("\n...\n").strip()
        result = rostool(["param", "set", f"/t/{key}", text], env)
        assert result.returncode == 0, result.stderr
        got = yaml.safe_load(debian(["rosparam", "get", f"/t/{key}"], env).stdout)
        assert got == value and type(got) is type(value), key
    # theirs -> ours: identical text for scalars and namespaces
    for key in EVERY_TYPE:
        assert (
            rostool(["param", "get", f"/t/{key}"], env).stdout
            == debian(["rosparam", "get", f"/t/{key}"], env).stdout
        )
    assert yaml.safe_load(rostool(["param", "get", "/t"], env).stdout) == EVERY_TYPE
    assert json.loads(rostool(["param", "get", "/t/nested", "--json"], env).stdout) == EVERY_TYPE["nested"]
    # their dump -> our load into a fresh namespace, and our dump -> their load
    their_file, our_file = tmp_path / "theirs.yaml", tmp_path / "ours.yaml"
    assert debian(["rosparam", "dump", str(their_file), "/t"], env).returncode == 0
    assert rostool(["param", "load", str(their_file), "/copy"], env).returncode == 0
    assert yaml.safe_load(debian(["rosparam", "get", "/copy"], env).stdout) == EVERY_TYPE
    assert rostool(["param", "dump", str(our_file), "/t"], env).returncode == 0
    assert yaml.safe_load(our_file.read_text()) == EVERY_TYPE
    assert debian(["rosparam", "load", str(our_file), "/again"], env).returncode == 0
    assert yaml.safe_load(rostool(["param", "get", "/again"], env).stdout) == EVERY_TYPE
    listed = rostool(["param", "list", "/t/nested"], env).stdout.split()
    assert listed == sorted(debian(["rosparam", "list", "/t/nested"], env).stdout.split())
    assert rostool(["param", "delete", "/t/yes"], env).returncode == 0
    assert debian(["rosparam", "get", "/t/yes"], env).returncode != 0


def test_book_w2_hello_world(book_master: dict[str, str], tmp_path: Path) -> None:
    """The book's W2: 5 Hz /hello_world publisher and subscriber, inspected with rostool."""
    env = book_master
    pub = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "publisher_script")
    sub = start_rospy_script(HELLO_SUBSCRIBER, env, tmp_path, "simple_subscriber")
    try:
        assert wait_until(
            lambda: "/hello_world_pub_node" in rostool(["node", "list"], env).stdout.split(), 20
        )
        assert "/hello_world" in rostool(["topic", "list"], env).stdout.split()
        echo = rostool(["topic", "echo", "/hello_world", "-n", "2"], env).stdout
        assert re.fullmatch(r'data: "Hello_World_\d+"\n---\ndata: "Hello_World_\d+"\n---\n', echo)
        info = rostool(["topic", "info", "/hello_world"], env).stdout
        assert info.startswith("Type: std_msgs/String\n\nPublishers: \n * /hello_world_pub_node (")
        assert " * /hello_world_sub_node (" in info
        hz = rostool(["topic", "hz", "/hello_world", "--duration", "2.2"], env).stdout
        assert "average rate: 5.0" in hz or "average rate: 4.9" in hz, hz
        assert sub.stdout is not None and sub.stdout.readline().startswith("Message received: Hello_World_")
    finally:
        stop(pub)
        stop(sub)


def test_book_w5_parameters(book_master: dict[str, str], tmp_path: Path) -> None:
    """The book's W5: rosdistro, /wheel_radius, dump and load, read back by a rospy node."""
    env = book_master
    listed = rostool(["param", "list"], env).stdout.split()
    assert {"/rosdistro", "/rosversion", "/run_id"} <= set(listed)
    assert (
        rostool(["param", "get", "/rosdistro"], env).stdout
        == debian(["rosparam", "get", "/rosdistro"], env).stdout
    )
    assert rostool(["param", "set", "/wheel_radius", "0.05"], env).returncode == 0
    assert rostool(["param", "get", "/wheel_radius"], env).stdout == "0.05\n"
    params = tmp_path / "params.yaml"
    assert rostool(["param", "dump", str(params)], env).returncode == 0
    dumped = yaml.safe_load(params.read_text())
    assert dumped["wheel_radius"] == 0.05 and "rosdistro" in dumped
    params.write_text(params.read_text().replace("wheel_radius: 0.05", "wheel_radius: 0.07"))
    assert rostool(["param", "load", str(params)], env).returncode == 0
    read_back = debian(
        [
            DEBIAN_PYTHON,
            "-c",
            "import rospy; rospy.init_node('reader'); print(rospy.get_param('/wheel_radius', 0.05))",
        ],
        env,
    )
    assert read_back.stdout.strip() == "0.07", read_back.stderr


def test_msg_show_and_md5_match_debian_generated_classes(debian_master: dict[str, str]) -> None:
    env = debian_master
    probe = """
import sys, json, roslib.message
out = {}
for name in sys.argv[1:]:
    cls = roslib.message.get_message_class(name)
    out[name] = [cls._md5sum, list(zip(cls.__slots__, cls._slot_types))]
print(json.dumps(out))
"""
    names = ["std_msgs/String", "geometry_msgs/PoseStamped", "sensor_msgs/LaserScan", "sensor_msgs/Image",
             "geometry_msgs/Twist", "std_msgs/Header"]  # fmt: skip
    theirs = json.loads(debian([DEBIAN_PYTHON, "-c", probe, *names], env).stdout)
    for name in names:
        md5, slots = theirs[name]
        assert rostool(["msg", "md5", name], env).stdout.strip() == md5
        shown = rostool(["msg", "show", name], env).stdout.splitlines()
        top_level = [line for line in shown if line and not line.startswith(" ") and "=" not in line]
        assert top_level == [f"{t} {n}" for n, t in slots], name


def test_param_set_mapping_updates_like_rosparam(debian_master: dict[str, str]) -> None:
    env = debian_master
    for tool in (rostool, debian):
        prefix = "/ours" if tool is rostool else "/theirs"
        command = ["param", "set"] if tool is rostool else ["rosparam", "set"]
        assert tool([*command, f"{prefix}/robot", "{name: r2, wheels: 4}"], env).returncode == 0
        assert tool([*command, f"{prefix}/robot", "{wheels: 6}"], env).returncode == 0
    ours = yaml.safe_load(debian(["rosparam", "get", "/ours/robot"], env).stdout)
    theirs = yaml.safe_load(debian(["rosparam", "get", "/theirs/robot"], env).stdout)
    assert ours == theirs == {"name": "r2", "wheels": 6}
