"""`rostool action` against Debian's rosmaster and an actionlib SimpleActionServer (rospy), built from the
book's MoveToPoint.action with genpy at test time."""

from __future__ import annotations

import json
import queue
import re
import subprocess
import threading
from pathlib import Path
from typing import IO

import pytest

from tests.support import (
    debian,
    debian_popen,
    interface_workspace,
    master_names,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
    wait_until,
    with_genpy_classes,
)

MOVE_ACTION = (
    "# Goal\ngeometry_msgs/Point point\n---\n# Result\nfloat32 elapsed_time\n---\n"
    "# Feedback\nfloat32 distance_to_point\n"
)
ACTION = "/navigate_2d_action"

# The book's server (Ch19) made runnable: the robot starts where /robot/point said, moves toward the goal
# at 2 m/s (10 steps a second) publishing the distance as feedback, and succeeds within 0.25 m.
NAV_SERVER = """
import math, time
import actionlib, rospy
from geometry_msgs.msg import Point
from robot_navigation_pkg.msg import MoveToPointAction, MoveToPointFeedback, MoveToPointResult

SPEED, HZ, THRESHOLD = 2.0, 10.0, 0.25

class Navigator:
    def __init__(self):
        self.position, self.busy = Point(), False
        rospy.Subscriber('robot/point', Point, self.on_point)
        self.server = actionlib.SimpleActionServer('navigate_2d_action', MoveToPointAction, self.execute,
                                                   auto_start=False)
        self.server.start()

    def on_point(self, point):  # where the robot is when a goal starts
        if not self.busy:
            self.position = point
        print("POSITION %.1f %.1f %.1f" % (point.x, point.y, point.z), flush=True)

    def execute(self, goal):
        self.busy = True
        try:
            self.navigate(goal)
        finally:
            self.busy = False

    def navigate(self, goal):
        started, rate, target = time.time(), rospy.Rate(HZ), goal.point
        goal_id = self.server.current_goal.get_goal_id().id
        print("GOAL %s %.1f %.1f %.1f" % (goal_id, target.x, target.y, target.z), flush=True)
        while not rospy.is_shutdown():
            p = self.position
            distance = math.dist((p.x, p.y, p.z), (target.x, target.y, target.z))
            if self.server.is_preempt_requested():
                print("PREEMPTED %s" % goal_id, flush=True)
                self.server.set_preempted(MoveToPointResult(elapsed_time=time.time() - started))
                return
            if distance <= THRESHOLD:
                print("SUCCEEDED %s" % goal_id, flush=True)
                self.server.set_succeeded(MoveToPointResult(elapsed_time=time.time() - started))
                return
            self.server.publish_feedback(MoveToPointFeedback(distance_to_point=distance))
            step = min(SPEED / HZ, distance) / distance
            self.position = Point(p.x + (target.x - p.x) * step, p.y + (target.y - p.y) * step,
                                  p.z + (target.z - p.z) * step)
            rate.sleep()

rospy.init_node('navigate_2D_action_server_node')
Navigator()
print("READY", flush=True)
rospy.spin()
"""


class Lines:
    """Reads a process's output on a thread, so tests can wait for a line with a deadline."""

    def __init__(self, stream: IO[str] | None) -> None:
        assert stream is not None
        self.seen: list[str] = []
        self._queue: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._pump, args=(stream,), daemon=True).start()

    def _pump(self, stream: IO[str]) -> None:
        for line in stream:
            self._queue.put(line)

    def wait_for(self, pattern: str, timeout: float = 20.0) -> re.Match[str]:
        for line in self.seen:
            if (found := re.search(pattern, line)) is not None:
                return found
        while True:
            try:
                line = self._queue.get(timeout=timeout)
            except queue.Empty:
                raise AssertionError(f"no line matching {pattern!r}; got {self.seen}") from None
            self.seen.append(line)
            if (found := re.search(pattern, line)) is not None:
                return found

    def rest(self) -> str:
        while True:
            try:
                self.seen.append(self._queue.get(timeout=0.5))
            except queue.Empty:
                return "".join(self.seen)


@pytest.fixture
def nav_env(debian_master: dict[str, str], tmp_path: Path) -> dict[str, str]:
    src = interface_workspace(
        tmp_path / "catkin_ws", {"robot_navigation_pkg/action/MoveToPoint.action": MOVE_ACTION}
    )
    return with_genpy_classes(debian_master, src, tmp_path)


def _start_server(env: dict[str, str], tmp_path: Path) -> tuple[subprocess.Popen[str], Lines]:
    server = start_rospy_script(NAV_SERVER, env, tmp_path, "action_server")
    lines = Lines(server.stdout)
    lines.wait_for("READY")
    # until the master knows the action's five topics (asked in process), then rostool's list must show it
    parts = {f"{ACTION}/{part}" for part in ("goal", "cancel", "status", "feedback", "result")}
    assert wait_until(lambda: parts <= master_names(env["ROS_MASTER_URI"])["topics"], 20), parts
    listed = rostool(["action", "list"], env)
    assert ACTION in listed.stdout.split(), listed.stderr
    return server, lines


def _feedback_distances(text: str) -> list[float]:
    return [float(d) for d in re.findall(r"^  distance_to_point: (\S+)$", text, re.M)]


def test_book_w12_robot_navigation(debian_roscore: dict[str, str], tmp_path: Path) -> None:
    src = interface_workspace(
        tmp_path / "catkin_ws", {"robot_navigation_pkg/action/MoveToPoint.action": MOVE_ACTION}
    )
    env = with_genpy_classes(debian_roscore, src, tmp_path)
    server, server_lines = _start_server(env, tmp_path)
    # the book's robot_point_pub.py: the robot's current position, published at 1 Hz
    position = rostool_popen(
        ["topic", "pub", "/robot/point", "geometry_msgs/Point", "0.0", "0.0", "0.0", "-r", "1"], env
    )
    try:
        server_lines.wait_for(r"POSITION 0.0 0.0 0.0")
        topics = rostool(["topic", "list"], env).stdout.split()
        assert {f"{ACTION}/{t}" for t in ("goal", "cancel", "feedback", "result", "status")} <= set(topics)
        assert (
            rostool(["topic", "type", f"{ACTION}/goal"], env).stdout
            == "robot_navigation_pkg/MoveToPointActionGoal\n"
        )
        assert rostool(["action", "list"], env).stdout == f"{ACTION}\n"
        info = rostool(["action", "info", ACTION], env).stdout
        server_line = "Server: \n * /navigate_2D_action_server_node\n"
        assert info.startswith(f"Action: {ACTION}\nType: robot_navigation_pkg/MoveToPoint\n{server_line}"), (
            info
        )
        assert info.endswith("Goals: None\n")
        assert rostool(["action", "show", "robot_navigation_pkg/MoveToPoint"], env).stdout.startswith(
            "geometry_msgs/Point point\n"
        )
        done = rostool(
            ["action", "send-goal", ACTION, "{point: {x: 1.0, y: 1.0, z: 0.0}}", "--feedback"], env
        )
        assert done.returncode == 0, done.stderr
        goal_id = re.match(r"Goal sent: (/rostool-\d+-1-\d+\.\d+)\n", done.stdout)
        assert goal_id is not None, done.stdout
        distances = _feedback_distances(done.stdout)
        assert distances[0] == pytest.approx(2**0.5, abs=0.25)
        assert distances == sorted(distances, reverse=True) and len(distances) >= 3
        assert distances[-1] > 0.25
        tail = done.stdout.split("Status: SUCCEEDED\nResult:\n", 1)[1]
        elapsed = re.fullmatch(r"  elapsed_time: (\S+)\n", tail)
        assert elapsed is not None and 0.2 < float(elapsed.group(1)) < 10
        server_lines.wait_for(f"SUCCEEDED {re.escape(goal_id.group(1))}")
        final = rostool(["action", "info", ACTION], env).stdout
        assert f" * {goal_id.group(1)}: SUCCEEDED" in final
    finally:
        stop(position)
        stop(server)


def test_ctrl_c_cancels_the_goal(nav_env: dict[str, str], tmp_path: Path) -> None:
    env = nav_env
    server, server_lines = _start_server(env, tmp_path)
    try:
        goal = rostool_popen(["action", "send-goal", ACTION, "{point: {x: 500.0}}", "--feedback"], env)
        ours = Lines(goal.stdout)
        goal_id = ours.wait_for(r"Goal sent: (\S+)").group(1)
        ours.wait_for(r"distance_to_point")
        active = rostool(["action", "info", ACTION], env).stdout
        assert f" * {goal_id}: ACTIVE" in active and "Clients: \n * /rostool_" in active, active
        goal.send_signal(2)  # Ctrl+C
        assert goal.wait(10) == 130
        assert goal.stderr is not None and goal.stderr.read() == ""
        server_lines.wait_for(f"PREEMPTED {re.escape(goal_id)}")
        text = ours.rest()
        assert "Status: PREEMPTED\nResult:\n  elapsed_time: " in text, text
    finally:
        stop(server)


def test_timeout_cancels_and_fails(nav_env: dict[str, str], tmp_path: Path) -> None:
    env = nav_env
    server, server_lines = _start_server(env, tmp_path)
    try:
        done = rostool(["action", "send-goal", ACTION, "{point: {y: -500.0}}", "--timeout", "1.5"], env)
        assert done.returncode == 1
        goal_id = re.match(r"Goal sent: (\S+)\n", done.stdout)
        assert goal_id is not None
        assert re.fullmatch(
            rf"rostool: goal {re.escape(goal_id.group(1))} got no result within 1.5 s; canceled it; "
            r"the server reports PREEMPTED\n",
            done.stderr,
        ), done.stderr
        server_lines.wait_for(f"PREEMPTED {re.escape(goal_id.group(1))}")
    finally:
        stop(server)


def test_cancel_by_id_and_all_json_events(nav_env: dict[str, str], tmp_path: Path) -> None:
    env = nav_env
    server, server_lines = _start_server(env, tmp_path)
    try:
        typed = [
            "action",
            "send-goal",
            ACTION,
            "robot_navigation_pkg/MoveToPoint",
            "{point: {z: 500.0}}",
            "--json",
        ]
        goal = rostool_popen(typed, env)
        events = Lines(goal.stdout)
        goal_id = json.loads(events.wait_for(r'"event": "sent"').string)["goal_id"]
        server_lines.wait_for(f"GOAL {re.escape(goal_id)}")
        cancel = rostool(["action", "cancel", ACTION, goal_id], env)
        assert cancel.stdout == f"canceled {goal_id} of {ACTION}\n", cancel.stderr
        assert goal.wait(10) == 1  # a goal that did not succeed
        result = json.loads(events.wait_for(r'"event": "result"').string)
        assert result["status"] == "PREEMPTED" and result["result"]["elapsed_time"] > 0
        server_lines.wait_for(f"PREEMPTED {re.escape(goal_id)}")

        second = rostool_popen(["action", "send-goal", ACTION, "{point: {x: -500.0}}"], env)
        second_lines = Lines(second.stdout)
        second_id = second_lines.wait_for(r"Goal sent: (\S+)").group(1)
        server_lines.wait_for(f"GOAL {re.escape(second_id)}")
        assert rostool(["action", "cancel", ACTION], env).stdout == f"canceled every goal of {ACTION}\n"
        assert second.wait(10) == 1
        server_lines.wait_for(f"PREEMPTED {re.escape(second_id)}")
        assert "Status: PREEMPTED" in second_lines.rest()
    finally:
        stop(server)


def test_their_rostopic_sees_our_goal(nav_env: dict[str, str], tmp_path: Path) -> None:
    """Our ActionGoal is the catkin-built type: Debian's rostopic decodes it with its generated class."""
    env = nav_env
    server, _server_lines = _start_server(env, tmp_path)
    echo = debian_popen(["rostopic", "echo", "-n", "1", f"{ACTION}/goal"], env)
    try:
        assert wait_until(lambda: "/rostopic" in rostool(["topic", "info", f"{ACTION}/goal"], env).stdout, 20)
        done = rostool(["action", "send-goal", ACTION, "{point: {x: 0.5, y: 0.0, z: 0.0}}"], env)
        assert done.returncode == 0, done.stderr
        out, _err = echo.communicate(timeout=20)
        goal_id = re.match(r"Goal sent: (\S+)\n", done.stdout)
        assert goal_id is not None
        assert (
            f'id: "{goal_id.group(1)}"' in out
            and "goal: \n  point: \n    x: 0.5\n    y: 0.0\n    z: 0.0" in out
        ), out
    finally:
        if echo.poll() is None:
            echo.kill()
        stop(server)


def test_bad_input_one_clear_line(nav_env: dict[str, str], tmp_path: Path) -> None:
    env = nav_env
    no_server = rostool(["action", "send-goal", "/nowhere", "{point: {x: 1}}"], env)
    assert (
        no_server.returncode == 1
        and "the type of action /nowhere is unknown: no server listens on /nowhere/goal" in (no_server.stderr)
    )
    typed = rostool(
        ["action", "send-goal", "/nowhere", "robot_navigation_pkg/MoveToPoint", "{}", "--timeout", "1"], env
    )
    assert (
        typed.returncode == 1 and "the action server of /nowhere did not connect within 1 s" in typed.stderr
    )
    unknown_type = rostool(["action", "send-goal", "/nowhere", "nav_pkg/Go", "{}"], env)
    assert "unknown action type nav_pkg/Go: no package nav_pkg found. Looked in:" in unknown_type.stderr
    server, _lines = _start_server(env, tmp_path)
    try:
        cases = {
            ("send-goal", ACTION, "{pont: {x: 1}}"): "has no field 'pont'; its fields are: point",
            ("send-goal", ACTION, "{point: {x: abc}}"): "field 'goal.point.x' is a float64; got 'abc'",
            ("send-goal", ACTION, "actionlib/TwoInts", "{a: 1}"): f"action {ACTION} has type "
            "robot_navigation_pkg/MoveToPoint, not actionlib/TwoInts",
            ("info", "/nope"): "no action /nope: it needs the topics /nope/{goal,cancel,status,feedback",
            ("cancel", ACTION, "/some-goal", "--all"): "give a GOAL_ID or --all, not both",
            ("cancel", "/nope", "--all"): "nothing listens on /nope/cancel",
        }
        for args, expected in cases.items():
            done = rostool(["action", *args], env)
            assert done.returncode == 1 and expected in done.stderr, (args, done.stderr)
            assert len(done.stderr.splitlines()) == 1 and done.stderr.startswith("rostool: ")
    finally:
        stop(server)
    assert debian(["rostopic", "list"], env).returncode == 0
