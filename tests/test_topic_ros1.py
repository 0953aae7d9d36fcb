"""`rostool topic` against Debian's real rosmaster, rospy nodes and rostopic, in both directions."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

import pytest

from tests.peers import FAST_PUBLISHER, HELLO_PUBLISHER, LATCHED_SCAN, TYPED_SUBSCRIBER
from tests.support import (
    debian,
    debian_popen,
    master_names,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
    wait_until,
)


def _wait_topic(env: dict[str, str], topic: str) -> None:
    """Until the master knows `topic` (asked in process), then rostool's list must show it."""
    assert wait_until(lambda: topic in master_names(env["ROS_MASTER_URI"])["topics"], 20), topic
    listed = rostool(["topic", "list"], env)
    assert topic in listed.stdout.split(), listed.stderr


def test_their_publisher_our_list_info_type_echo(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    pub = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    try:
        _wait_topic(env, "/hello_world")
        assert rostool(["topic", "type", "/hello_world"], env).stdout == "std_msgs/String\n"
        ours, theirs = (
            rostool(["topic", "info", "/hello_world"], env),
            debian(["rostopic", "info", "/hello_world"], env),
        )
        assert ours.stdout == theirs.stdout
        assert "/hello_world_pub_node" in ours.stdout
        verbose = rostool(["topic", "list", "-v"], env).stdout
        assert " * /hello_world [std_msgs/String] 1 publisher" in verbose
        listed = json.loads(rostool(["topic", "list", "--json"], env).stdout)
        hello = next(t for t in listed if t["name"] == "/hello_world")
        assert hello == {"name": "/hello_world", "type": "std_msgs/String",
                         "publishers": ["/hello_world_pub_node"], "subscribers": []}  # fmt: skip
        echo = rostool(["topic", "echo", "/hello_world", "-n", "3"], env)
        blocks = echo.stdout.split("---\n")
        values = [int(m) for m in re.findall(r'^data: "Hello_World_(\d+)"$', echo.stdout, re.M)]
        assert len(values) == 3 and values == list(range(values[0], values[0] + 3)), echo.stdout
        assert blocks[-1] == ""
        as_json = rostool(["topic", "echo", "/hello_world", "--once", "--json"], env)
        assert json.loads(as_json.stdout)["data"].startswith("Hello_World_")
        assert rostool(["topic", "find", "std_msgs/String"], env).stdout.split() == ["/hello_world"]
    finally:
        stop(pub)


def test_echo_matches_rostopic_echo_byte_for_byte(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    node = start_rospy_script(LATCHED_SCAN, env, tmp_path, "scan")
    try:
        _wait_topic(env, "/pose")
        # a filter that drops every message: its 2 s wait for one runs beside the other runs
        dropping = rostool_popen(
            ["topic", "echo", "/scan", "--timeout", "2", "--filter", "m.header.frame_id == 'map'"], env
        )
        for topic in ("/scan", "/pose"):
            ours = rostool(["topic", "echo", topic, "-n", "1"], env).stdout
            theirs = debian(["rostopic", "echo", "-n", "1", topic], env).stdout
            # seq is per connection in rospy; everything else must match exactly
            assert re.sub(r"seq: \d+", "seq: N", ours) == re.sub(r"seq: \d+", "seq: N", theirs)
        noarr = rostool(["topic", "echo", "/scan", "-n", "1", "--noarr"], env).stdout
        assert 'ranges: "<array type: float32, length: 3>"' in noarr
        field = rostool(["topic", "echo", "/pose", "-n", "1", "--field", "pose.position.x"], env).stdout
        assert field == "0.1\n---\n"
        csv = rostool(["topic", "echo", "/pose", "-n", "1", "--csv"], env).stdout.splitlines()
        assert csv[0].startswith("%time,field.header.seq,field.header.stamp,field.header.frame_id")
        assert csv[1].startswith("3000000007,") and ",map,0.1," in csv[1]
        kept = rostool(["topic", "echo", "/scan", "-n", "1", "--json", "--filter", "m.ranges[1] > 1.1"], env)
        assert json.loads(kept.stdout)["ranges"] == [1.0, 1.2000000476837158, 0.8999999761581421]
        dropped, _err = dropping.communicate(timeout=30)
        assert dropping.returncode == 1 and dropped == ""
    finally:
        stop(node)


def test_our_publisher_their_echo_and_subscriber(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    ours = rostool(["topic", "pub", "/point", "geometry_msgs/Point", "1.0", "2.0", "3.0", "-1"], env)
    assert ours.returncode == 0, ours.stderr
    # latched for 3 s and gone afterwards: a fresh publisher for the real rostopic echo
    pub = rostool_popen(
        ["topic", "pub", "/vel", "geometry_msgs/Twist", "{linear: {x: 0.5}, angular: {z: -1}}"], env
    )
    try:
        theirs = debian(["rostopic", "echo", "-n", "1", "/vel"], env, timeout=20)
        assert (
            "linear: \n  x: 0.5\n  y: 0.0\n  z: 0.0\nangular: \n  x: 0.0\n  y: 0.0\n  z: -1.0"
            in theirs.stdout
        )
    finally:
        stop(pub)
    sub = start_rospy_script(TYPED_SUBSCRIBER, env, tmp_path, "typed", ["/chatter", "std_msgs/String"])
    try:
        assert sub.stdout is not None and sub.stdout.readline().strip() == "READY"
        rate_pub = rostool_popen(
            ["topic", "pub", "/chatter", "std_msgs/String", "data: hi there", "-r", "20"], env
        )
        line = sub.stdout.readline()
        _out, err = stop(rate_pub)
        assert line.strip() == 'data: "hi there"', line
        assert rate_pub.returncode == 130 and "Traceback" not in err
    finally:
        stop(sub)
    # our publisher unregistered on Ctrl+C and their subscriber is gone: no trace of /chatter
    assert "/chatter" not in debian(["rostopic", "list"], env).stdout.split()


@pytest.mark.alone
def test_hz_counts_a_real_publisher(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    pub = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    try:
        _wait_topic(env, "/hello_world")
        out = rostool(["topic", "hz", "/hello_world", "--duration", "3.2"], env).stdout
        assert out.startswith("subscribed to [/hello_world]\n")
        rates = [float(r) for r in re.findall(r"average rate: ([\d.]+)", out)]
        assert rates and all(abs(r - 5.0) < 0.25 for r in rates), out
        assert re.search(r"\tmin: 0\.\d{3}s max: 0\.\d{3}s std dev: \d\.\d{5}s window: \d+", out)
    finally:
        stop(pub)


def test_hz_json_and_several_topics(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    hello = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    fast = debian_popen(["/usr/bin/python3", "-c", FAST_PUBLISHER, "50"], env)
    try:
        _wait_topic(env, "/hello_world")
        _wait_topic(env, "/fast")
        out = rostool(["topic", "hz", "/hello_world", "/fast", "--json", "--duration", "3.2"], env).stdout
        last = {}
        for line in out.splitlines():
            report = json.loads(line)
            last[report["topic"]] = report["rate"]
        assert abs(last["/hello_world"] - 5) < 0.3 and abs(last["/fast"] - 50) < 3, out
        table = rostool(["topic", "hz", "/hello_world", "/fast", "--duration", "2.2"], env).stdout
        assert "topic" in table and "rate" in table and "/fast" in table
    finally:
        stop(hello)
        stop(fast)


def test_bw_and_delay(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    pub = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    try:
        _wait_topic(env, "/hello_world")
        out = rostool(["topic", "bw", "/hello_world", "--duration", "2.5"], env).stdout
        # "Hello_World_N" serializes to a 4-byte length + 13..15 characters
        assert re.search(r"average: [\d.]+B/s\n\tmean: 1[7-9]\.\d\dB min: ", out), out
    finally:
        stop(pub)
    stamped = rostool_popen(
        ["topic", "pub", "/stamped", "geometry_msgs/PointStamped", "{header: {stamp: now}}", "-r", "20"], env
    )
    try:
        _wait_topic(env, "/stamped")
        out = rostool(["topic", "delay", "/stamped", "--duration", "2.5"], env).stdout
        assert re.search(r"average delay: \d+\.\d{3}\n\tmin: ", out), out
    finally:
        stop(stamped)


def test_no_stale_registration_after_ctrl_c(debian_master: dict[str, str]) -> None:
    env = debian_master
    echo = rostool_popen(["topic", "echo", "/nobody"], env)
    assert wait_until(lambda: "/nobody" in debian(["rostopic", "list"], env).stdout.split(), 10)
    _out, err = stop(echo)
    assert echo.returncode == 130 and "Traceback" not in err
    state = debian(["rostopic", "info", "/nobody"], env)
    assert "Subscribers: None" in state.stdout or state.returncode != 0
    assert not [n for n in debian(["rosnode", "list"], env).stdout.split() if n.startswith("/rostool")]


def test_our_publisher_survives_subscribers_coming_and_going(debian_master: dict[str, str]) -> None:
    env = debian_master
    pub = rostool_popen(["topic", "pub", "/count", "std_msgs/Int32", "7", "-r", "50"], env)
    try:
        for _ in range(3):
            theirs = debian(["rostopic", "echo", "-n", "2", "/count"], env, timeout=20)
            assert theirs.stdout == "data: 7\n---\ndata: 7\n---\n", theirs.stderr
    finally:
        _out, err = stop(pub)
    assert "Traceback" not in err
    time.sleep(0.2)


def test_unknown_type_is_decoded_from_the_publishers_definition(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    from tests.peers import CUSTOM_TYPE_PUBLISHER

    env = debian_master
    pub = start_rospy_script(CUSTOM_TYPE_PUBLISHER, env, tmp_path, "custom")
    try:
        assert pub.stdout is not None
        md5 = pub.stdout.readline().strip()
        _wait_topic(env, "/temperature")
        assert rostool(["topic", "type", "/temperature"], env).stdout == "book_msgs/TemperatureStatus\n"
        ours = rostool(["topic", "echo", "/temperature", "-n", "1"], env).stdout
        assert ours == (
            'temperature: 31.0\nthreshold: 30.0\nstatus: "ALERT"\nhistory: [29, 30, 31]\n'
            "where: \n  x: 1.5\n  y: 0.0\n  z: 0.0\n---\n"
        )
        as_json = json.loads(rostool(["topic", "echo", "/temperature", "-n", "1", "--json"], env).stdout)
        assert as_json["history"] == [29, 30, 31] and as_json["where"]["x"] == 1.5
        # rostopic needs the type's package installed and cannot print it at all
        assert debian(["rostopic", "echo", "-n", "1", "/temperature"], env, timeout=20).stdout == ""
        assert len(md5) == 32
    finally:
        stop(pub)


def test_pub_custom_type_from_a_source_tree_without_a_build(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    from tests.support import interface_workspace, with_genpy_classes

    text = "float32 temperature\nstring status\nint16[] history\ngeometry_msgs/Point where\n"
    src = interface_workspace(tmp_path, {"book_msgs/msg/TemperatureStatus.msg": text})
    theirs_env = with_genpy_classes(debian_master, src, tmp_path)  # only Debian's rostopic needs a build
    ours_env = {k: v for k, v in debian_master.items() if k != "ROS_PACKAGE_PATH"}
    value = "{temperature: 31.5, status: ALERT, history: [29, 30], where: {x: 1.5}}"
    pub = rostool_popen(
        ["topic", "pub", "/status", "book_msgs/TemperatureStatus", value, "--interfaces", str(src)], ours_env
    )
    try:
        theirs = debian(["rostopic", "echo", "-n", "1", "/status"], theirs_env, timeout=30)
        expected = 'temperature: 31.5\nstatus: "ALERT"\nhistory: [29, 30]\n'
        expected += "where: \n  x: 1.5\n  y: 0.0\n  z: 0.0\n---\n"
        assert theirs.stdout == expected, theirs.stderr
    finally:
        _out, err = stop(pub)
    assert "Traceback" not in err
    missing = rostool(
        ["topic", "pub", "/status", "book_msgs/Nope", "{}", "-1", "--interfaces", str(src)], ours_env
    )
    assert missing.returncode != 0 and "unknown message type book_msgs/Nope" in missing.stderr
    assert str(src) in missing.stderr  # says where it looked
