"""`rostool doctor hello` (ros2 doctor hello) between private machines (tests/netns.py): the laptop and the
robot beside it hear each other on /canyouhearme and by multicast, the far robot behind the router hears
neither; ros2's summary table line for line; both ROS 2 backends, a real rclpy Jazzy node hearing the
laptop's hellos, and ROS 1 through rostool's master on the robot. Never in the host's own network namespace
(CONTRIBUTING, "Network rule").
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from tests.netns import PrivateNetwork, user_env
from tests.ros2_peers import RclpyPeer, machine_peer_env, peer_python, rclpy_command
from tests.support import fresh_domain, wait_until

HELLO = [sys.executable, "-m", "rostool", "doctor", "hello"]
RULE = "-" * 60
# one summary as ros2doctor's SummaryTable.format_print_summary prints it: each table row is
# '{:<15} {:<20} {:<10}' of ('', host, count), so 16 spaces, the host padded to 20, a space, the count padded
SUMMARY = re.compile(
    r"MULTIMACHINE COMMUNICATION SUMMARY\n"
    r"Topic: (?P<topic>\S+), Published Msg Count: (?P<published>\d+)\n"
    r"Subscribed from:\n"
    r" {16}Hostname {13}Msg Count /(?P<period>[0-9.]+)s\n"
    r"(?P<subscribed>(?: {16}\S.{19} \d+ *\n)*)"
    r"Multicast Group/Port: 225\.0\.0\.1/49150, Sent Msg Count: (?P<sent>\d+)\n"
    r"Received from:\n"
    r" {16}Hostname {13}Msg Count /(?P=period)s\n"
    r"(?P<received>(?: {16}\S.{19} \d+ *\n)*)"
    rf"{RULE}\n"
)


def machine_env(**settings: str) -> dict[str, str]:
    """A user's shell on a private machine: no ROS variable but the test's domain and `settings`."""
    return user_env(ROS_DOMAIN_ID=str(fresh_domain()), **settings)


def _rows(block: str) -> dict[str, int]:
    rows = {}
    for line in block.splitlines():
        host, count = line.split()
        assert line == f"{'':16}{host:<20} {count:<10}", repr(line)  # ros2's padding, trailing spaces too
        rows[host] = int(count)
    return rows


def summaries(out: str) -> list[dict[str, Any]]:
    """The summary tables of a run's stdout, which must hold nothing else."""
    found, at = [], 0
    while at < len(out):
        match = SUMMARY.match(out, at)
        assert match, f"not a summary table at {out[at : at + 300]!r}"
        found.append({
            "topic": match["topic"], "period": match["period"], "published": int(match["published"]),
            "sent": int(match["sent"]), "subscribed_from": _rows(match["subscribed"]),
            "received_from": _rows(match["received"]),
        })  # fmt: skip
        at = match.end()
    return found


def heard(tables: list[dict[str, Any]], side: str) -> dict[str, int]:
    """Every host heard on one side ("subscribed_from": the topic, "received_from": multicast), summed."""
    total: dict[str, int] = {}
    for table in tables:
        for host, count in table[side].items():
            total[host] = total.get(host, 0) + count
    return total


def finished(process: subprocess.Popen[str], timeout: float = 60) -> str:
    out, err = process.communicate(timeout=timeout)
    assert (process.returncode, err) == (0, ""), (process.returncode, err, out[-2000:])
    return out


def test_once_prints_ros2s_table_for_one_emit(network: PrivateNetwork) -> None:
    """ros2doctor's test_hello_single_host: one hello published and sent, nobody heard, one summary."""
    started = time.monotonic()
    done = network.far.run([*HELLO, "-1"], machine_env())
    assert (done.returncode, done.stderr) == (0, ""), done
    assert done.stdout == (
        "MULTIMACHINE COMMUNICATION SUMMARY\n"
        "Topic: /canyouhearme, Published Msg Count: 1\n"
        "Subscribed from:\n"
        "                Hostname             Msg Count /1.0s\n"
        "Multicast Group/Port: 225.0.0.1/49150, Sent Msg Count: 1\n"
        "Received from:\n"
        "                Hostname             Msg Count /1.0s\n"
        "------------------------------------------------------------\n"
    )
    assert time.monotonic() - started < 20


def test_laptop_and_robot_hear_each_other_the_far_robot_neither(network: PrivateNetwork) -> None:
    """All three at once on rostool's DDS backend with ROS's defaults: each of the laptop and the robot names
    the other on the topic and by multicast, in ros2's table; the far robot (its summaries as JSON) hears
    nobody, neither on the topic (SUBNET discovery stops at the router) nor by multicast, until Ctrl+C."""
    env = machine_env()
    emits = 30
    argv = [*HELLO, "-n", str(emits), "-pp", "0.5"]
    far = network.far.popen([*HELLO, "--json"], env)
    laptop, robot = network.laptop.popen(argv, env), network.robot.popen(argv, env)
    tables = {"laptop": summaries(finished(laptop)), "robot": summaries(finished(robot))}
    far.send_signal(signal.SIGINT)
    far_out, far_err = far.communicate(timeout=30)
    for me, other in (("laptop", "robot"), ("robot", "laptop")):
        mine = tables[me]
        assert {(t["topic"], t["period"]) for t in mine} == {("/canyouhearme", "0.5")}
        assert sum(t["published"] for t in mine) == sum(t["sent"] for t in mine) == emits
        on_topic, by_multicast = heard(mine, "subscribed_from"), heard(mine, "received_from")
        assert set(on_topic) == set(by_multicast) == {other}, (me, mine)
        assert 0 < on_topic[other] <= emits and 0 < by_multicast[other] <= emits
    assert (far.returncode, far_err) == (130, "")
    far_tables = [json.loads(line) for line in far_out.splitlines()]
    assert len(far_tables) >= 2, far_out  # it ran through the others' whole run
    for table in far_tables:
        assert table == {
            "topic": "/canyouhearme", "group": "225.0.0.1", "port": 49150, "period": 1.0,
            "published": table["published"], "subscribed_from": {}, "sent": table["published"],
            "received_from": {},
        }  # fmt: skip
        assert 5 <= table["published"] <= 20  # 10 a second, give or take a loaded machine's pauses


def test_real_rclpy_node_hears_the_laptop_on_the_rclpy_backend(
    network: PrivateNetwork, tmp_path: Path
) -> None:
    """The laptop on the rclpy backend (Jazzy's rclpy, Fast DDS), the robot on the DDS backend (Cyclone) and a
    real rclpy Jazzy node on the robot listening to /canyouhearme: the real node hears both hosts' hellos
    word for word, and each rostool names the other on the topic and by multicast."""
    peer_python("jazzy")
    env = machine_env()
    listener = RclpyPeer(
        "jazzy", env, tmp_path, ["--name", "ear", "--listen", "/canyouhearme"], on=network.robot
    )
    try:
        listener.wait_for("ready")
        # the robot says hello for longer: the laptop's rclpy starts a second or two later
        robot = network.robot.popen([*HELLO, "-n", "60"], env)
        laptop_argv = rclpy_command(["doctor", "hello", "-n", "40"], "jazzy")
        laptop = network.laptop.popen(laptop_argv, machine_peer_env(env, tmp_path))
        laptop_tables, robot_tables = summaries(finished(laptop)), summaries(finished(robot))
        assert wait_until(lambda: {"laptop", "robot"} <= _hosts(listener), timeout=5), listener.of("heard")
    finally:
        listener.stop()
    assert {e["topic"] for e in listener.of("heard")} == {"/canyouhearme"}
    assert sum(t["published"] for t in laptop_tables) == 40
    assert sum(t["published"] for t in robot_tables) == 60
    for mine, other in ((laptop_tables, "robot"), (robot_tables, "laptop")):
        assert set(heard(mine, "subscribed_from")) == set(heard(mine, "received_from")) == {other}, mine


def _hosts(peer: RclpyPeer) -> set[str]:
    """The hosts whose hellos the real node heard ("hello, it's me HOST", ros2's text)."""
    said = {event["data"] for event in peer.of("heard")}
    assert all(text.startswith("hello, it's me ") for text in said), said
    return {text.removeprefix("hello, it's me ") for text in said}


def test_ros1_through_a_master_on_the_robot(network: PrivateNetwork) -> None:
    """ROS 1: rostool's master on the robot, each machine with ROS_MASTER_URI and its ROS_IP: the laptop and
    the robot hear each other on the topic (TCPROS) and by multicast."""
    robot_ip, laptop_ip = network.robot.address, network.laptop.address
    env = machine_env(ROS_MASTER_URI=f"http://{robot_ip}:11311")
    master = network.robot.popen([sys.executable, "-m", "rostool", "core", "--host", "0.0.0.0"],
                                 {**env, "ROS_IP": robot_ip})  # fmt: skip
    try:
        assert master.stderr is not None
        started = master.stderr.readline()
        assert started.startswith(f"started rostool core at http://{robot_ip}:11311/"), started
        argv = [*HELLO, "-n", "25"]
        laptop = network.laptop.popen(argv, {**env, "ROS_IP": laptop_ip})
        robot = network.robot.popen(argv, {**env, "ROS_IP": robot_ip})
        tables = {"laptop": summaries(finished(laptop)), "robot": summaries(finished(robot))}
    finally:
        master.send_signal(signal.SIGINT)
        master.communicate(timeout=10)
    for me, other in (("laptop", "robot"), ("robot", "laptop")):
        mine = tables[me]
        assert sum(t["published"] for t in mine) == 25
        assert set(heard(mine, "subscribed_from")) == set(heard(mine, "received_from")) == {other}, mine


def test_doctor_options_do_not_go_with_a_verb() -> None:
    """`rostool doctor`'s own options before `hello`: a usage error, before anything runs."""
    done = subprocess.run([*HELLO[:-1], "--json", "--report", "hello"], capture_output=True, text=True,
                          timeout=30)  # fmt: skip
    assert done.returncode == 2 and done.stdout == ""
    assert "--report, --json: options of `rostool doctor` alone, not of its verbs" in done.stderr
