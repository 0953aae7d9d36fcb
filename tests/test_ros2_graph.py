"""ROS 2 over DDS: rostool processes talk to each other the way ROS 2 nodes do (loopback, no multicast).

Every test uses its own ROS_DOMAIN_ID and LOCALHOST discovery, said explicitly (interface 127.0.0.1,
multicast off, 127.0.0.1 as the only peer), so nothing leaves the machine and tests never see each other.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import TESTDATA, ros2_env, rostool, rostool_popen, stop, wait_until


@pytest.fixture
def env() -> dict[str, str]:
    return ros2_env()


@pytest.fixture
def chatter(env: dict[str, str]) -> Iterator[subprocess.Popen[str]]:
    """A rostool publisher of std_msgs/String on /chatter at 10 Hz."""
    proc = rostool_popen(["topic", "pub", "/chatter", "std_msgs/String", "data: hello ros2", "-r", "10"], env)
    yield proc
    stop(proc)


def yaml_docs(text: str) -> list[str]:
    return [doc.strip() for doc in text.split("---") if doc.strip()]


def test_pub_echo_list_type_info_find(env: dict[str, str], chatter: subprocess.Popen[str]) -> None:
    echo = rostool(["topic", "echo", "/chatter", "-n", "3"], env)
    assert echo.returncode == 0, echo.stderr
    assert yaml_docs(echo.stdout) == ["data: hello ros2"] * 3

    as_json = rostool(["topic", "echo", "chatter", "-n", "1", "--json"], env)
    assert json.loads(as_json.stdout) == {"data": "hello ros2"}

    listed = rostool(["topic", "list"], env)
    assert listed.stdout.split() == ["/chatter"], listed.stderr
    verbose = rostool(["topic", "list", "-v"], env).stdout
    assert " * /chatter [std_msgs/msg/String] 1 publisher" in verbose
    assert rostool(["topic", "type", "/chatter"], env).stdout == "std_msgs/msg/String\n"
    assert rostool(["topic", "find", "std_msgs/String"], env).stdout == "/chatter\n"
    assert rostool(["topic", "find", "std_msgs/msg/String"], env).stdout == "/chatter\n"

    info = rostool(["topic", "info", "/chatter"], env).stdout
    assert info.splitlines() == ["Type: std_msgs/msg/String", "Publisher count: 1", "Subscription count: 0"]
    detail = rostool(["topic", "info", "/chatter", "-v", "--json"], env)
    (endpoint,) = json.loads(detail.stdout)["endpoints"]
    assert endpoint["node"] == f"/rostool_{chatter.pid}"
    assert endpoint["endpoint_type"] == "PUBLISHER"
    assert endpoint["qos"] == {"reliability": "reliable", "durability": "volatile", "depth": 10}
    # Jazzy endpoints announce REP 2016's type hash in USER_DATA (rosbags computes the same one)
    assert endpoint["type_hash"] == "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"


def test_node_list_and_info_show_both_processes(env: dict[str, str], chatter: subprocess.Popen[str]) -> None:
    listener = rostool_popen(["topic", "echo", "/chatter"], env)
    try:
        assert listener.stdout is not None
        assert listener.stdout.readline() == "data: hello ros2\n"
        talker_node, listener_node = f"/rostool_{chatter.pid}", f"/rostool_{listener.pid}"
        nodes = rostool(["node", "list"], env)
        assert nodes.stdout.split() == sorted([talker_node, listener_node]), nodes.stderr

        info = rostool(["node", "info", talker_node], env).stdout.splitlines()
        assert info[0] == talker_node
        assert info[info.index("  Publishers:") + 1] == "    /chatter: std_msgs/msg/String"
        listening = json.loads(rostool(["node", "info", listener_node, "--json"], env).stdout)
        assert listening["subscribers"] == [{"name": "/chatter", "type": "std_msgs/msg/String"}]
        assert listening["publishers"] == []

        counts = rostool(["topic", "info", "/chatter"], env).stdout
        assert "Publisher count: 1\nSubscription count: 1" in counts
    finally:
        stop(listener)


@pytest.mark.alone
def test_hz_and_bw_count_a_rostool_publisher(env: dict[str, str]) -> None:
    pub = rostool_popen(["topic", "pub", "/fast", "std_msgs/Int32", "data: 7", "-r", "20"], env)
    try:
        # side by side (bw measures sizes, not time), so the suite's serial end is one window long
        measuring = rostool_popen(["topic", "bw", "/fast", "--duration", "2.2"], env)
        out = rostool(["topic", "hz", "/fast", "--json", "--duration", "3.2"], env).stdout
        bw = measuring.communicate(timeout=30)[0]
        reports = [json.loads(line) for line in out.splitlines()]
        assert reports, out
        assert abs(reports[-1]["rate"] - 20.0) < 2.0, reports[-1]
        # std_msgs/Int32 in CDR: 4 bytes of encapsulation header + 4 bytes of data
        assert "Message size mean: 8 B min: 8 B max: 8 B" in bw, bw  # ros2 topic bw's form
    finally:
        stop(pub)


def test_qos_adapts_to_best_effort_and_transient_local(env: dict[str, str]) -> None:
    sensor_qos = ["--qos-profile", "sensor_data"]
    best_effort = rostool_popen(
        ["topic", "pub", "/scan_like", "std_msgs/String", "data: be", "-r", "20", *sensor_qos], env
    )
    latched = rostool_popen(["topic", "pub", "/map_like", "std_msgs/Int32", "data: 42", "-l"], env)
    try:
        # A reliable reader never matches a best-effort writer: echo must subscribe best_effort itself.
        got = rostool(["topic", "echo", "/scan_like", "-n", "2"], env)
        assert yaml_docs(got.stdout) == ["data: be"] * 2, got.stderr
        detail = json.loads(rostool(["topic", "info", "/scan_like", "-v", "--json"], env).stdout)
        offered = detail["endpoints"][0]["qos"]
        assert offered == {"reliability": "best_effort", "durability": "volatile", "depth": 5}

        # Published once, long before this echo starts: only a transient_local reader receives it.
        assert wait_until(lambda: "/map_like" in rostool(["topic", "list"], env).stdout, 10)
        late = rostool(["topic", "echo", "/map_like", "-n", "1", "--timeout", "10"], env)
        assert yaml_docs(late.stdout) == ["data: 42"], late.stderr
        volatile = rostool(
            ["topic", "echo", "/map_like", "-n", "1", "--timeout", "2", "--qos-durability", "volatile"], env
        )
        assert volatile.returncode == 1 and "no message within 2 s" in volatile.stderr

        # Asking for more than the publisher offers: the incompatible policy is named.
        wrong = rostool(["topic", "echo", "/scan_like", "-n", "1", "--qos-reliability", "reliable"], env)
        assert wrong.returncode == 1
        assert "incompatible policy RELIABILITY" in wrong.stderr, wrong.stderr
    finally:
        stop(best_effort)
        stop(latched)


def test_echo_follows_the_publishers_qos_as_they_change(env: dict[str, str]) -> None:
    """ros2 topic echo picks its QoS once; rostool's echo subscribes again when a publisher it cannot
    match appears (and the user left the QoS to it), so every publisher below is heard."""
    echo = rostool_popen(["topic", "echo", "/y"], env)
    volatile = rostool_popen(["topic", "echo", "/y", "--qos-durability", "volatile"], env)
    try:
        time.sleep(1.0)
        # latched (transient_local): echo adapts to it; the volatile echo still gets it, because a
        # finite publication waits for the subscribers discovery shows before publishing
        assert rostool(["topic", "pub", "/y", "std_msgs/String", "data: b", "-1"], env).returncode == 0
        for data, extra in (("c", []), ("e", ["--qos-reliability", "best_effort"])):
            sent = rostool(["topic", "pub", "/y", "std_msgs/String", f"data: {data}", "-r", "5", "-n", "2",
                            *extra], env)  # fmt: skip
            assert sent.returncode == 0, sent.stderr
        time.sleep(0.5)
    finally:
        out, err = stop(echo)
        out_volatile, _err = stop(volatile)
    assert yaml_docs(out) == ["data: b", "data: c", "data: c", "data: e", "data: e"], err
    assert yaml_docs(out_volatile)[0] == "data: b"


# Publishes every message of a bag as its stored CDR bytes, once every topic has its subscribers.
PUBLISH_BAG = r"""
import json, sys, time
from rostool.bag.reader import BagReader
from rostool.graph.ros2_base.qos import QosRequest
from rostool.graph.ros2.graph import Ros2Graph

bag, wanted = sys.argv[1], json.loads(sys.argv[2])
graph = Ros2Graph()
with BagReader([bag]) as reader:
    rows = [(conn.topic, conn.msgtype, bytes(raw)) for conn, _t, raw in reader.messages()]
    graph.types.register(reader.resolver.store.fielddefs)
graph.qos_request = QosRequest(depth=0)
pubs = {}
for topic, msgtype, _raw in rows:
    pubs.setdefault(topic, graph.publisher(topic, msgtype))
for topic, pub in pubs.items():
    if not pub.wait_for_subscribers(wanted.get(topic, 1), 20):
        sys.exit(f"no subscriber on {topic}")
for topic, _msgtype, raw in rows:
    pubs[topic].publish_raw(raw)
print("sent", len(rows), flush=True)
sys.stdin.read()
graph.close()
"""

# Subscribes to the given topics and prints the payloads it received, as hex, once it has them all.
RECEIVE = r"""
import json, sys, threading
from rostool.bag.reader import BagReader
from rostool.graph.ros2_base.qos import QosRequest
from rostool.graph.ros2.graph import Ros2Graph

bag, expected = sys.argv[1], json.loads(sys.argv[2])
graph = Ros2Graph()
with BagReader([bag]) as reader:
    graph.types.register(reader.resolver.store.fielddefs)
graph.qos_request = QosRequest(depth=0)
got = {topic: [] for topic in expected}
done = threading.Event()

def on_message(received):
    got[received.topic].append(received.payload.hex())
    received.decode()
    if all(len(got[t]) >= n for t, n in expected.items()):
        done.set()

for topic in expected:
    graph.subscribe(topic, on_message, lambda e: sys.exit(e))
done.wait(40)
print(json.dumps(got), flush=True)
graph.close()
"""


def bag_payloads(bag: Path) -> dict[str, list[str]]:
    from rostool.bag.reader import BagReader

    found: dict[str, list[str]] = {}
    with BagReader([bag]) as reader:
        for conn, _t, raw in reader.messages():
            found.setdefault(conn.topic, []).append(bytes(raw).hex())
    return found


@pytest.mark.parametrize("bag", ["talker_mcap", "cdr_test_mcap"])
def test_recorded_ros2_bytes_arrive_byte_for_byte(env: dict[str, str], bag: str) -> None:
    path = TESTDATA / "ros2" / bag
    expected = bag_payloads(path)
    counts = {topic: len(payloads) for topic, payloads in expected.items()}
    receiver = subprocess.Popen(
        [sys.executable, "-c", RECEIVE, str(path), json.dumps(counts)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    wanted = {"/topic": 2} if bag == "talker_mcap" else {}
    publisher = subprocess.Popen(
        [sys.executable, "-c", PUBLISH_BAG, str(path), json.dumps(wanted)],
        env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        if bag == "talker_mcap":  # the CLI decodes what the real talker sent
            echo = rostool(["topic", "echo", "/topic", "-n", "3", "--json"], env)
            assert [json.loads(line) for line in echo.stdout.splitlines()] == [
                {"data": f"Hello, world! {i}"} for i in range(3)
            ], echo.stderr
        out, err = receiver.communicate(timeout=60)
        assert receiver.returncode == 0, err
        assert json.loads(out) == expected
        assert any(len(bytes.fromhex(p)) > 600 for p in expected.get("/array_topic", ["00" * 601]))
    finally:
        if receiver.poll() is None:
            receiver.kill()
        publisher.communicate(input="", timeout=20)


def test_bad_input_gives_one_clear_line(env: dict[str, str]) -> None:
    out_of_range = rostool(["topic", "list"], {**env, "ROS_DOMAIN_ID": "233"})
    assert out_of_range.returncode == 1
    assert out_of_range.stderr == "rostool: ROS_DOMAIN_ID='233' is not valid: use an integer from 0 to 232\n"

    unknown = rostool(["topic", "pub", "/x", "nope_msgs/Thing", "{}", "-1"], env)
    assert unknown.returncode == 1
    assert "unknown message type 'nope_msgs/Thing'" in unknown.stderr
    assert "jazzy type store" in unknown.stderr and "Traceback" not in unknown.stderr

    no_version = {k: v for k, v in env.items() if k != "ROS_VERSION"}
    empty = rostool(["--ros2", "node", "list"], no_version)  # the root flag instead of ROS_VERSION=2
    assert empty.returncode == 1
    assert f"no ROS 2 participants found on domain {env['ROS_DOMAIN_ID']} within 3 s" in empty.stderr

    bad_range = rostool(["topic", "list"], {**env, "ROS_AUTOMATIC_DISCOVERY_RANGE": "GALAXY"})
    assert bad_range.returncode == 1 and "ROS_AUTOMATIC_DISCOVERY_RANGE='GALAXY'" in bad_range.stderr

    ros1 = rostool(["--ros1", "topic", "hz", "/x", "--qos-depth", "5"], {**env, "ROS_VERSION": "1"})
    assert ros1.returncode == 1
    assert ros1.stderr == "rostool: --qos-* options apply to ROS 2 graphs only: ROS 1 topics have no QoS\n"

    params = rostool(["param", "get", "/x"], env)
    assert params.returncode == 1 and "ROS 2 parameters" in params.stderr
