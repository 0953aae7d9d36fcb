"""`rostool graph`, `bag graph`, `bag plot`, `topic plot`: against real Debian ROS 1 nodes, real rclpy nodes
and real bags; drawings are read back (SVG text and line data) and compared with what the graph or the
bag holds."""

from __future__ import annotations

import itertools
import json
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.peers import FAST_PUBLISHER
from tests.ros2_peers import RclpyPeer, StartPeer
from tests.support import TESTDATA, debian_popen, master_names, start_rospy_script, stop, wait_until
from tests.support import rostool as run_rostool

SVG = "{http://www.w3.org/2000/svg}"
EXAMPLE_BAG = TESTDATA / "ros1" / "example.bag"

LISTENER = """
import rospy
from std_msgs.msg import String
rospy.init_node('listener')
rospy.Subscriber('chatter', String, lambda msg: None)
rospy.spin()
"""


def rostool(args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """The CLI with room for matplotlib's import and drawing on a loaded machine."""
    return run_rostool(args, env, timeout=120)


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
        assert text[0] == "2 nodes, 1 topic"
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
        code, tree = run_in_terminal(["graph"], env)  # a terminal gets rich's tree
        assert code == 0 and "└── " in tree and "pub /chatter [std_msgs/String] -> /listener" in tree, tree
        png = rostool(["graph", "-o", str(tmp_path / "graph.png")], env)
        assert png.returncode == 0 and (tmp_path / "graph.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    finally:
        stop(listener)
        stop(talker)


# --- rostool graph: ROS 2 ---------------------------------------------------------------------------------
def test_graph_of_a_real_rclpy_talker_and_listener(
    graph_env: dict[str, str], start_peer: StartPeer, tmp_path: Path
) -> None:
    # names of this test only: another test run may share the DDS domain on a busy machine
    ns, topic = f"/gp{os.getpid()}", f"/chatter{os.getpid()}"
    start_peer.together(
        ["--name", "talker", "--namespace", ns, "--talk", topic, "--service", f"{ns}/enable"],
        ["--name", "listener", "--namespace", ns + "_l", "--listen", topic],
    )
    talker, listener = f"{ns}/talker", f"{ns}_l/listener"

    def connected() -> bool:
        found = json.loads(rostool(["graph", "--json"], graph_env).stdout or '{"topics": []}')
        return any(t["name"] == topic and t["subscribers"] == [listener] for t in found["topics"])

    assert wait_until(connected, 30)
    listed = check_drawn(["graph"], graph_env, tmp_path)
    assert {talker, listener} <= set(listed["nodes"])  # type: ignore[arg-type]
    chatter = {
        "name": topic,
        "type": "std_msgs/msg/String",
        "publishers": [talker],
        "subscribers": [listener],
    }
    assert chatter in listed["topics"]  # type: ignore[operator]
    assert "/rosout" not in {t["name"] for t in listed["topics"]}  # type: ignore[attr-defined]
    every = json.loads(rostool(["graph", "--all", "--json"], graph_env).stdout)
    assert {"/rosout", "/parameter_events"} <= {t["name"] for t in every["topics"]}
    inside = json.loads(rostool(["graph", "--ns", ns, "--services", "--json"], graph_env).stdout)
    # the node's own parameter services are left out unless --all
    assert inside["services"] == [
        {"name": f"{ns}/enable", "type": "std_srvs/srv/SetBool", "servers": [talker], "clients": []}
    ]
    assert inside["nodes"] == [talker]
    assert inside["topics"] == [{**chatter, "subscribers": []}]  # the listener is outside NS


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


# --- rostool bag plot -------------------------------------------------------------------------------------
def echo_values(args: list[str], field: str) -> list[float]:
    """One number per message, from `rostool bag echo --json --field` (the referee for the plot)."""
    out = rostool(["bag", "echo", *args, "--json", "--field", field], dict(os.environ)).stdout
    return [float(json.loads(line)) for line in out.splitlines()]


def csv_series(text: str) -> dict[str, list[tuple[float, float]]]:
    lines = text.splitlines()
    assert lines[0] == "time,series,value"
    found: dict[str, list[tuple[float, float]]] = {}
    for line in lines[1:]:
        when, name, value = line.split(",")
        found.setdefault(name, []).append((float(when), float(value)))
    return found


def svg_lines(path: Path) -> dict[str, list[tuple[float, float]]]:
    """Each plotted series' points in data units: pixel vertices mapped back through the axis ticks."""
    root = ET.parse(path).getroot()

    def ticks(axis: str) -> tuple[float, float]:
        pairs = []  # (pixel, value)
        for group in root.iter(f"{SVG}g"):
            if not re.fullmatch(rf"{axis}tick_\d+", group.get("id", "")):
                continue
            mark = next(group.iter(f"{SVG}use"))
            label = "".join("".join(t.itertext()) for t in group.iter(f"{SVG}text")).replace("\u2212", "-")
            pairs.append((float(mark.get(axis) or 0), float(label)))
        (p0, v0), (p1, v1) = pairs[0], pairs[-1]
        scale = (v1 - v0) / (p1 - p0)
        return scale, v0 - p0 * scale

    (xs, x0), (ys, y0) = ticks("x"), ticks("y")
    found = {}
    for group in root.iter(f"{SVG}g"):
        name = group.get("id", "")
        if name.startswith("series:"):
            d = next(group.iter(f"{SVG}path")).get("d", "")
            pixels = [(float(a), float(b)) for a, b in re.findall(r"[ML] ([-\d.e]+) ([-\d.e]+)", d)]
            found[name.removeprefix("series:")] = [(x * xs + x0, y * ys + y0) for x, y in pixels]
    return found


def test_bag_plot_has_every_value_of_bag_echo(tmp_path: Path) -> None:
    bag, env = str(EXAMPLE_BAG), dict(os.environ)
    linear = echo_values([bag, "/turtle1/cmd_vel"], "linear.x")
    angular = echo_values([bag, "/turtle2/cmd_vel"], "angular.z")
    assert len(linear) == 357 and len(angular) == 208
    paths = ["/turtle1/cmd_vel/linear/x", "/turtle2/cmd_vel.angular.z"]
    series = csv_series(rostool(["bag", "plot", bag, *paths], env).stdout)  # a pipe: CSV
    assert [v for _t, v in series[paths[0]]] == linear
    assert [v for _t, v in series[paths[1]]] == angular
    drawn = rostool(["bag", "plot", bag, *paths, "-o", str(tmp_path / "plot.svg")], env)
    assert drawn.returncode == 0, drawn.stderr
    lines = svg_lines(tmp_path / "plot.svg")
    assert [len(lines[p]) for p in paths] == [357, 208]
    for path, values in zip(paths, (linear, angular), strict=True):
        ys = [y for _x, y in lines[path]]
        span = max(values) - min(values)
        assert abs(min(ys) - min(values)) < span / 100 and abs(max(ys) - max(values)) < span / 100
        xs = [x for x, _y in lines[path]]  # seconds since the first point of both series
        first = min(series[paths[0]][0][0], series[paths[1]][0][0])
        assert abs(xs[-1] - (series[path][-1][0] - first)) < 0.1
    assert set(paths) <= svg_texts(tmp_path / "plot.svg")  # the legend names them
    png = rostool(["bag", "plot", bag, paths[0], "-o", str(tmp_path / "plot.png")], env)
    assert png.returncode == 0 and (tmp_path / "plot.png").read_bytes()[:4] == b"\x89PNG"


def test_bag_plot_time_range_header_stamp_and_message_fields() -> None:
    bag, env = str(EXAMPLE_BAG), dict(os.environ)
    window = ["--start", "+5", "--end", "+10"]
    expected = echo_values([bag, "/turtle1/pose", *window], "x")
    series = csv_series(rostool(["bag", "plot", bag, "/turtle1/pose", *window], env).stdout)
    assert list(series) == [f"/turtle1/pose/{f}" for f in ("x", "y", "theta", "linear_velocity",
                                                            "angular_velocity")]  # fmt: skip
    assert [v for _t, v in series["/turtle1/pose/x"]] == expected and 0 < len(expected) < 1344
    out = rostool(["bag", "echo", bag, "/rosout", "--json", "--field", "header.stamp"], env).stdout
    stamps = [json.loads(line) for line in out.splitlines()]
    by_stamp = csv_series(rostool(["bag", "plot", bag, "/rosout/level", "--header-stamp"], env).stdout)
    assert [t for t, _v in by_stamp["/rosout/level"]] == [s["secs"] + s["nsecs"] / 1e9 for s in stamps]
    ros2 = str(TESTDATA / "ros2" / "cdr_test_mcap")
    values = csv_series(rostool(["bag", "plot", ros2, "/test_topic/int32_value"], env).stdout)
    assert [v for _t, v in values["/test_topic/int32_value"]] == echo_values(
        [ros2, "/test_topic"], "int32_value"
    )
    wrong = rostool(["bag", "plot", bag, "/rosout/msg"], env)
    assert wrong.returncode == 1 and wrong.stderr.startswith("rostool: /rosout/msg is not a number")
    assert len(wrong.stderr.splitlines()) == 1
    missing = rostool(["bag", "plot", bag, "/nope/x"], env)
    assert missing.returncode == 1 and "no such topic" in missing.stderr


def run_in_terminal(
    args: list[str], env: dict[str, str], interrupt_when: Callable[[str], bool] | None = None
) -> tuple[int, str]:
    """rostool with its stdout on a pseudo-terminal of 100x30, Ctrl+C once `interrupt_when(output)` holds:
    (exit code, all it drew)."""
    import fcntl
    import struct
    import termios

    leader, follower = pty.openpty()
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    proc = subprocess.Popen([sys.executable, "-m", "rostool", *args], env=env, stdout=follower,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)  # fmt: skip
    os.close(follower)
    output = b""
    started = time.monotonic()
    while time.monotonic() < started + 120:
        if interrupt_when is not None and interrupt_when(output.decode(errors="replace")):
            proc.send_signal(signal.SIGINT)
            interrupt_when = None
        ready, _, _ = select.select([leader], [], [], 0.5)
        if ready:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the process closed the terminal
                break
            if not chunk:
                break
            output += chunk
        elif proc.poll() is not None:
            break
    os.close(leader)
    code = proc.wait(timeout=60)
    assert proc.stderr is not None
    err = proc.stderr.read().decode()
    return code, output.decode(errors="replace") + err


BRAILLE = re.compile("[\u2801-\u28ff]")


def test_bag_plot_draws_in_a_terminal() -> None:
    paths = ["/turtle1/cmd_vel/linear/x", "/turtle2/pose/theta"]
    code, text = run_in_terminal(["bag", "plot", str(EXAMPLE_BAG), *paths], dict(os.environ))
    assert code == 0, text
    assert len(BRAILLE.findall(text)) > 100 and all(p in text for p in paths)
    piped = rostool(["bag", "plot", str(EXAMPLE_BAG), *paths], dict(os.environ)).stdout.splitlines()
    first = piped[1].split(",")[0]  # exact decimal seconds of the first point
    assert f"seconds since {first[: first.index('.') + 4]} " in text


def test_a_missing_plot_extra_is_one_line(tmp_path: Path) -> None:
    probe = ("import sys; sys.modules['matplotlib'] = None; sys.argv = ['rostool'] + sys.argv[1:]\n"
             "from rostool.cli import main; main()")  # fmt: skip
    args = ["bag", "plot", str(EXAMPLE_BAG), "/turtle1/pose/x", "-o", str(tmp_path / "x.png")]
    done = subprocess.run([sys.executable, "-c", probe, *args], capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert done.stderr == "rostool: matplotlib is not installed: pip install 'rostool[plot]'\n"
    assert not (tmp_path / "x.png").exists()


# --- rostool topic plot -----------------------------------------------------------------------------------
def test_topic_plot_live_ros1(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    counter = start_rospy_script(FAST_PUBLISHER, env, tmp_path, "counter", ["20"])
    try:
        assert wait_until(lambda: "/fast" in master_names(env["ROS_MASTER_URI"])["topics"], 20)
        piped = rostool(["topic", "plot", "/fast/data", "--duration", "5"], env)
        values = [v for _t, v in csv_series(piped.stdout)["/fast/data"]]
        assert len(values) >= 20 and values == [values[0] + i for i in range(len(values))], piped.stdout
        svg = tmp_path / "live.svg"

        def enough(text: str) -> bool:  # the last frame's status line
            counts = re.findall(r"(\d+) points in the last", text)
            return bool(counts) and int(counts[-1]) >= 30

        code, text = run_in_terminal(["topic", "plot", "/fast.data", "-o", str(svg)], env, enough)
        assert code == 0, text
        assert len(BRAILLE.findall(text)) > 20 and "/fast.data" in text
        (points,) = svg_lines(svg).values()
        ys = [y for _x, y in points]
        assert len(points) >= 20 and ys[-1] - ys[0] == pytest.approx(len(points) - 1, abs=0.5)
    finally:
        stop(counter)


def test_topic_plot_live_ros2_header_stamp(
    graph_env: dict[str, str], start_peer: Callable[..., RclpyPeer]
) -> None:
    start_peer("--name", "stamper", "--stamped", "/point", "--rate", "10")
    done = rostool(["topic", "plot", "/point/point/x", "--header-stamp", "--duration", "6"], graph_env)
    rows = csv_series(done.stdout)["/point/point/x"]
    times, values = [t for t, _v in rows], [v for _t, v in rows]
    assert len(rows) >= 10 and values == [values[0] + i for i in range(len(rows))], done.stdout
    gaps = [b - a for a, b in itertools.pairwise(times)]
    assert min(gaps) > 0 and 0.05 < sum(gaps) / len(gaps) < 0.2  # the stamps of a 10 Hz timer
    assert abs(times[-1] - time.time()) < 30
