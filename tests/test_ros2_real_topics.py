"""Topics and nodes against real rclpy nodes (Jazzy and Kilted, Fast DDS): the ROS 2 referee.

rostool runs with its defaults (DDS over Cyclone, LOCALHOST discovery); the peers run rmw_fastrtps_cpp with a
loopback-only profile (tests/ros2_peers.py). Values are asserted on both sides: what rostool prints and
what the real node received or saw.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable

import pytest

from tests.ros2_peers import RclpyPeer, StartPeer
from tests.support import rostool, rostool_popen, side_by_side, stop

Start = Callable[..., RclpyPeer]


def docs(text: str) -> list[str]:
    return [doc.strip() for doc in text.split("---") if doc.strip()]


def test_topic_list_finds_a_real_publisher_every_time(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter")
    # ten listings, each a fresh participant discovering the graph, plus the typed forms: side by side
    asked = [["topic", "list"]] * 10 + [
        ["topic", "list", "-v"], ["topic", "type", "/chatter"], ["topic", "find", "std_msgs/msg/String"]
    ]  # fmt: skip
    *listings, verbose, typed, found = side_by_side([lambda a=args: rostool(a, graph_env) for args in asked])
    for listed in listings:
        assert "/chatter" in listed.stdout.split(), listed.stderr
    assert " * /chatter [std_msgs/msg/String] 1 publisher" in verbose.stdout
    assert typed.stdout == "std_msgs/msg/String\n"
    assert found.stdout == "/chatter\n"


def test_node_list_and_info_show_the_real_node(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--namespace", "/robot", "--talk", "/chatter", "--listen", "/heard")
    nodes, as_json, as_text = side_by_side([
        lambda: rostool(["node", "list"], graph_env),
        lambda: rostool(["node", "info", "/robot/talker", "--json"], graph_env),
        lambda: rostool(["node", "info", "/robot/talker"], graph_env),
    ])  # fmt: skip
    assert "/robot/talker" in nodes.stdout.split(), nodes.stderr
    info = json.loads(as_json.stdout)
    assert {"name": "/chatter", "type": "std_msgs/msg/String"} in info["publishers"]
    assert {"name": "/heard", "type": "std_msgs/msg/String"} in info["subscribers"]
    # rclpy's own services (parameters, type description) belong to the node
    service_names = [s["name"] for s in info["service_servers"]]
    assert "/robot/talker/list_parameters" in service_names
    text = as_text.stdout.splitlines()
    assert text[0] == "/robot/talker"
    assert "    /chatter: std_msgs/msg/String" in text


def test_topic_info_verbose_names_the_real_node(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--best-effort", "--depth", "7")
    detail = rostool(["topic", "info", "/chatter", "-v", "--json"], graph_env)
    (endpoint,) = json.loads(detail.stdout)["endpoints"]
    assert endpoint["node"] == "/talker"
    assert endpoint["endpoint_type"] == "PUBLISHER"
    assert endpoint["qos"]["reliability"] == "best_effort"
    assert endpoint["qos"]["depth"] is None  # Fast DDS does not announce its history: unknown, as ros2 says
    # REP 2016's hash as rosidl computed it for the real node equals rosbags' hash of the same type
    assert endpoint["type_hash"] == "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"


def test_echo_receives_the_real_publishers_messages(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    echo, once = side_by_side([
        lambda: rostool(["topic", "echo", "/chatter", "-n", "3", "--json"], graph_env),
        lambda: rostool(["topic", "echo", "/chatter", "-n", "1"], graph_env),
    ])  # fmt: skip
    assert echo.returncode == 0, echo.stderr
    values = [json.loads(line)["data"] for line in echo.stdout.splitlines()]
    numbers = [int(v.removeprefix("hello ")) for v in values]
    assert numbers == list(range(numbers[0], numbers[0] + 3))
    assert docs(once.stdout)[0].startswith("data: hello ")


@pytest.mark.alone
def test_hz_at_10_hz_and_1_khz(graph_env: dict[str, str], start_peer: StartPeer) -> None:
    """hz agrees within 2 % with the rate the publisher itself counted over the same seconds (a Python
    publisher on a loaded machine does not keep exactly 1 kHz, so the nominal rate is no referee)."""
    slow, fast = start_peer.together(  # side by side: while they start, this test holds the whole suite
        ["--name", "slow", "--talk", "/slow", "--rate", "10"],
        ["--name", "fast", "--talk", "/fast", "--rate", "1000", "--depth", "1000"],
    )
    talkers = {"/slow": slow, "/fast": fast}
    # both measured in the same window (the suite's serial end is one window long, not two)
    before = {topic: len(peer.of("published")) for topic, peer in talkers.items()}
    running = {topic: rostool_popen(["topic", "hz", topic, "--json", "--duration", "5.2"], graph_env)
               for topic in talkers}  # fmt: skip
    outs = {topic: proc.communicate(timeout=60)[0] for topic, proc in running.items()}
    for topic, peer in talkers.items():
        out = outs[topic]
        reports = [json.loads(line) for line in out.splitlines()]
        assert reports, out
        during = peer.of("published")[before[topic] + 1 :]
        true_rate = (during[-1]["count"] - during[0]["count"]) / (during[-1]["t"] - during[0]["t"])
        assert abs(reports[-1]["rate"] - true_rate) / true_rate < 0.02, (topic, true_rate, reports[-1])


def test_bw_measures_the_real_cdr_size(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    out = rostool(["topic", "bw", "/chatter", "--duration", "2.2"], graph_env).stdout
    # "hello N" (N < 1000): 4 encapsulation + 4 length + 7..9 characters and a NUL, which Fast DDS pads
    # to a multiple of 4 (the encapsulation options count the padding): 20 bytes on the wire
    means = re.findall(r"Message size mean: ([\d.]+) B", out)  # ros2 topic bw's form
    assert means and float(means[-1]) == 20.0, out


def test_pub_reaches_the_real_subscriber(graph_env: dict[str, str], start_peer: Start) -> None:
    peer = start_peer("--name", "listener", "--listen", "/heard")
    once = rostool(["topic", "pub", "/heard", "std_msgs/msg/String", "data: from rostool", "-1"], graph_env)
    assert once.returncode == 0, once.stderr
    assert peer.wait_for("heard")["data"] == "from rostool"
    again = ["topic", "pub", "/heard", "std_msgs/String", "data: again", "-r", "20"]
    repeated = rostool_popen(again, graph_env)
    try:
        peer.wait_for("heard", lambda e: e["data"] == "again")
    finally:
        stop(repeated)


# Kilted's rmw_fastrtps keys a remote endpoint's node by the PID_PARTICIPANT_GUID of its SEDP data, which
# Cyclone never sends (Fast DDS 3 then leaves it zero; Jazzy derives it from the GUID prefix), so a Kilted
# node files the endpoints of every Cyclone participant, rmw_cyclonedds_cpp's too, under no node.
BARE = "_CREATED_BY_BARE_DDS_APP_/_CREATED_BY_BARE_DDS_APP_"


def test_a_real_node_sees_rostool_as_a_node(
    graph_env: dict[str, str], start_peer: Start, distro: str
) -> None:
    watcher = start_peer("--name", "watcher", "--watch")
    pub = rostool_popen(["topic", "pub", "/from_rostool", "std_msgs/String", "data: x", "-r", "5"], graph_env)
    echo = rostool_popen(["topic", "echo", "/from_rostool"], graph_env)
    me_pub, me_sub = f"/rostool_{pub.pid}", f"/rostool_{echo.pid}"
    owner_pub, owner_sub = (BARE, BARE) if distro == "kilted" else (me_pub, me_sub)
    try:

        def complete(event: dict) -> bool:
            return (
                me_pub in event["nodes"]
                and me_sub in event["nodes"]
                and event["publishers"].get("/from_rostool") == [owner_pub]
                and event["subscribers"].get("/from_rostool") == [owner_sub]
                and event["topics"].get("/from_rostool") == ["std_msgs/msg/String"]
            )

        try:
            watcher.wait_for("graph", complete, timeout=20)
        except AssertionError:
            raise AssertionError(f"{me_pub}, {me_sub} not in {watcher.of('graph')[-1:]}") from None
    finally:
        stop(pub)
        stop(echo)


def test_bad_input_on_a_real_graph(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "talker", "--talk", "/chatter")
    cases = (
        (["node", "info", "/nobody"], "/nobody"),
        (["topic", "echo", "/nothing", "--timeout", "1"], "Could not determine the type"),  # ros2's line
        (["topic", "pub", "/chatter", "std_msgs/msg/Nope", "data: 1", "-1"], "std_msgs/msg/Nope"),
    )
    runs = side_by_side([lambda a=args: rostool(a, graph_env, timeout=20) for args, _words in cases])
    for (args, words), done in zip(cases, runs, strict=True):
        assert done.returncode != 0, args
        # one error line (echo first warns that nothing publishes the topic, as ros2 topic echo does)
        lines = [line for line in done.stderr.strip().splitlines() if not line.startswith("WARNING: ")]
        assert len(lines) == 1 and words in lines[0], (args, done.stderr)
        assert "Traceback" not in done.stderr


def test_a_users_cyclonedds_uri_choosing_lo_wins(graph_env: dict[str, str], start_peer: Start) -> None:
    """A common set-up: LOCALHOST discovery and a CYCLONEDDS_URI that selects interface `lo` (Cyclone
    refuses an interface selected twice, so rostool leaves the interfaces to the user's file)."""
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    interfaces = '<Interfaces><NetworkInterface name="lo"/></Interfaces>'
    uri = f'<CycloneDDS><Domain Id="any"><General>{interfaces}</General></Domain></CycloneDDS>'
    echo = rostool(["topic", "echo", "/chatter", "-n", "1", "--json"], {**graph_env, "CYCLONEDDS_URI": uri})
    assert echo.returncode == 0, echo.stderr
    assert json.loads(echo.stdout)["data"].startswith("hello ")
