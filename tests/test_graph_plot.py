"""`rostool graph`, `bag graph`, `bag plot`, `topic plot`: against real Debian ROS 1 nodes, real rclpy nodes
and real bags; drawings are read back (SVG text and line data) and compared with what the graph or the
bag holds."""

from __future__ import annotations

import json
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

from tests.ros2_peers import RclpyPeer
from tests.support import TESTDATA, debian_popen, rostool, start_rospy_script, stop, wait_until

SVG = "{http://www.w3.org/2000/svg}"
EXAMPLE_BAG = TESTDATA / "ros1" / "example.bag"

LISTENER = """
import rospy
from std_msgs.msg import String
rospy.init_node('listener')
rospy.Subscriber('chatter', String, lambda msg: None)
rospy.spin()
"""


def svg_texts(path: Path) -> set[str]:
    return {"".join(t.itertext()).strip() for t in ET.parse(path).getroot().iter(f"{SVG}text")}


def dot_labels(text: str) -> set[str]:
    return set(re.findall(r'label="([^"]*)"', text))


def check_drawn(args: list[str], env: dict[str, str], tmp_path: Path) -> dict[str, object]:
    """The JSON graph, and the DOT and the SVG name exactly its nodes and topics."""
    listed = json.loads(rostool([*args, "--json"], env).stdout)
    names = set(listed["nodes"]) | {t["name"] for t in listed["topics"]}
    dot = rostool([*args, "--dot"], env)
    assert dot_labels(dot.stdout) == names, dot.stdout
    drawn = rostool([*args, "-o", str(tmp_path / "graph.svg")], env)
    assert drawn.returncode == 0, drawn.stderr
    assert svg_texts(tmp_path / "graph.svg") == names
    return listed


# --- rostool graph: ROS 1 ---------------------------------------------------------------------------------
def test_graph_of_a_real_ros1_graph(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    talker = debian_popen(["rostopic", "pub", "/chatter", "std_msgs/String", "data: hi", "-r", "5"], env)
    listener = start_rospy_script(LISTENER, env, tmp_path, "listener")
    try:

        def connected() -> bool:
            found = json.loads(rostool(["topic", "list", "--json"], env).stdout or "[]")
            chatter = next((t for t in found if t["name"] == "/chatter"), None)
            return chatter is not None and chatter["subscribers"] == ["/listener"]

        assert wait_until(connected, 30)
        listed = check_drawn(["graph"], env, tmp_path)
        chatter = next(t for t in listed["topics"] if t["name"] == "/chatter")  # type: ignore[attr-defined]
        (publisher,) = chatter["publishers"]
        assert publisher.startswith("/rostopic_") and chatter["subscribers"] == ["/listener"]
        assert chatter["type"] == "std_msgs/String"
        assert set(listed["nodes"]) == {publisher, "/listener"}  # type: ignore[arg-type]
        assert "/rosout" not in {t["name"] for t in listed["topics"]}  # type: ignore[attr-defined]
        every = json.loads(rostool(["graph", "--all", "--json"], env).stdout)
        rosout = next(t for t in every["topics"] if t["name"] == "/rosout")
        assert "/listener" in rosout["publishers"]  # rostopic pub does not log to /rosout
        text = rostool(["graph"], env).stdout.splitlines()
        assert text[0] == "2 nodes, 1 topics"
        assert "/listener" in text and "  pub /chatter [std_msgs/String] -> /listener" in text
        assert f"  sub /chatter [std_msgs/String] <- {publisher}" in text
        services = json.loads(rostool(["graph", "--services", "--json"], env).stdout)["services"]
        assert services == []  # only get_loggers/set_logger_level, left out unless --all
        every = json.loads(rostool(["graph", "--services", "--all", "--json"], env).stdout)["services"]
        assert {
            "name": "/listener/get_loggers",
            "type": None,
            "servers": ["/listener"],
            "clients": [],
        } in every
        assert json.loads(rostool(["graph", "--ns", "/nowhere", "--json"], env).stdout)["nodes"] == []
        png = rostool(["graph", "-o", str(tmp_path / "graph.png")], env)
        assert png.returncode == 0 and (tmp_path / "graph.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    finally:
        stop(listener)
        stop(talker)


# --- rostool graph: ROS 2 ---------------------------------------------------------------------------------
def test_graph_of_a_real_rclpy_talker_and_listener(
    graph_env: dict[str, str], start_peer: Callable[..., RclpyPeer], tmp_path: Path
) -> None:
    start_peer("--name", "talker", "--namespace", "/robot", "--talk", "/chatter")
    start_peer("--name", "listener", "--listen", "/chatter")

    def connected() -> bool:
        found = json.loads(rostool(["graph", "--json"], graph_env).stdout or '{"topics": []}')
        return any(t["name"] == "/chatter" and t["subscribers"] == ["/listener"] for t in found["topics"])

    assert wait_until(connected, 30)
    listed = check_drawn(["graph"], graph_env, tmp_path)
    assert listed["nodes"] == ["/listener", "/robot/talker"]
    assert listed["topics"] == [
        {"name": "/chatter", "type": "std_msgs/msg/String",
         "publishers": ["/robot/talker"], "subscribers": ["/listener"]},
    ]  # fmt: skip
    every = json.loads(rostool(["graph", "--all", "--json"], graph_env).stdout)
    assert {"/rosout", "/parameter_events"} <= {t["name"] for t in every["topics"]}
    robot = json.loads(rostool(["graph", "--ns", "/robot", "--json"], graph_env).stdout)
    assert robot["nodes"] == ["/robot/talker"]
    assert robot["topics"][0]["subscribers"] == []  # /listener is outside /robot


# --- rostool bag graph ------------------------------------------------------------------------------------
def test_bag_graph_lists_topics_types_and_recording_nodes(tmp_path: Path) -> None:
    env = dict(os.environ)
    listed = json.loads(rostool(["bag", "graph", str(EXAMPLE_BAG), "--json"], env).stdout)
    info = json.loads(rostool(["bag", "info", str(EXAMPLE_BAG), "--json"], env).stdout)
    assert [(t["name"], t["type"], t["count"]) for t in listed["topics"]] == [
        (t["name"], t["type"], t["count"]) for t in info["topics"]
    ]
    cmd_vel = next(t for t in listed["topics"] if t["name"] == "/turtle1/cmd_vel")
    assert cmd_vel == {"name": "/turtle1/cmd_vel", "type": "geometry_msgs/Twist", "publishers": ["/teleop"],
                       "subscribers": [], "count": 357}  # fmt: skip
    rosout = next(t for t in listed["topics"] if t["name"] == "/rosout")
    assert len(rosout["publishers"]) == 3 and "/sim" in rosout["publishers"]
    check_drawn(["bag", "graph", str(EXAMPLE_BAG)], env, tmp_path)
    ros2 = json.loads(rostool(["bag", "graph", str(TESTDATA / "ros2" / "talker_mcap"), "--json"], env).stdout)
    assert [(t["name"], t["type"]) for t in ros2["topics"]] == [
        ("/parameter_events", "rcl_interfaces/msg/ParameterEvent"),
        ("/rosout", "rcl_interfaces/msg/Log"),
        ("/topic", "std_msgs/msg/String"),
    ]
