"""ROS 2 actions through rclpy: rmw lists them, rclpy's ActionClient sends goals and follows them, and the
cancel service is called as the DDS backend calls it. Goals, feedback and results cross between rosbags'
messages (which the renderers print) and rclpy's classes through their CDR bytes, so the output is the DDS
backend's."""

from __future__ import annotations

import contextlib
import queue
import threading
import time
import uuid
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.rclpy import types as rtypes
from rostool.graph.ros2 import actions as ros2_actions
from rostool.graph.ros2.actions import (
    ACTION_INFIX,
    CANCEL_ERRORS,
    CANCEL_SERVICE,
    CANCEL_WAIT,
    ActionSummary,
    CancelingGoal,
    GoalEvent,
    GoalOutcome,
    GoalTimeout,
)
from rostool.graph.ros2.names import resolve
from rostool.interfaces import ros2_action
from rostool.interfaces.ros2_action import ActionTypes

if TYPE_CHECKING:
    from rostool.graph.base import GoalWatcher
    from rostool.graph.rclpy.graph import RclpyGraph


def register_action(graph: RclpyGraph, action_type: str) -> tuple[ActionTypes, Any]:
    """The action's store names (built in, from .action sources, else described from rclpy's classes) and
    the class rclpy imports."""
    name = ros2_action.action_store_name(action_type)
    cls = rtypes.python_class(name)
    try:
        found = ros2_action.register_action(graph.types, name)
    except RostoolError:
        found = ActionTypes(name)
        for part in ("Goal", "Result", "Feedback", "FeedbackMessage", "SendGoal_Request", "SendGoal_Response",
                     "GetResult_Request", "GetResult_Response"):  # fmt: skip
            rtypes.ensure_known(graph.types, found.part(part))
    return found, cls


def _wait(future: Any, deadline: float) -> bool:
    """Wait for an rclpy future until `deadline` (monotonic); whether it is done."""
    done = threading.Event()
    future.add_done_callback(lambda _f: done.set())
    while not done.wait(0.02):
        if time.monotonic() >= deadline:
            return False
    return True


def _server_ready(client: Any, deadline: float) -> bool:
    while not client.server_is_ready():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.02)
    return True


def list_actions(graph: RclpyGraph) -> list[ActionSummary]:
    """Actions with a server (a `<action>/_action/send_goal` service), with their client nodes."""
    found: dict[str, ActionSummary] = {}
    for name, type_, servers, clients in graph.service_endpoints():
        split = ros2_actions.split_action_service(name)
        if split is None or split[1] != "send_goal":
            continue
        found[split[0]] = ActionSummary(split[0], type_.removesuffix("_SendGoal"), servers, clients)
    return [found[name] for name in sorted(found)]


def cancel_goals(graph: RclpyGraph, name: str, goal_id: str | None) -> list[CancelingGoal]:
    action = graph.resolve(name)
    wanted = ros2_actions.parse_goal_id(goal_id) if goal_id is not None else bytes(16)
    response = _cancel(graph, action, wanted, 5.0)
    what = f"goal {wanted.hex()}" if goal_id is not None else "every goal"
    if response.return_code != 0:
        why = CANCEL_ERRORS.get(response.return_code, f"return code {response.return_code}")
        raise RostoolError(f"canceling {what} of {action} failed: {why}")
    return [CancelingGoal(bytes(g.goal_id.uuid).hex(), g.stamp) for g in response.goals_canceling]


def _cancel(graph: RclpyGraph, action: str, goal_id: bytes, timeout: float) -> Any:
    """Ask the action's server to cancel `goal_id` (all zeros: every goal); the CancelGoal response."""
    client = graph.service_client(action + ACTION_INFIX + "cancel_goal", CANCEL_SERVICE)
    try:
        if not client.wait_for_server(timeout):
            raise RostoolError(
                f"no action server for {action} matched within {timeout:g} s (see `rostool action list`)"
            )
        info = {"goal_id": {"uuid": list(goal_id)}}  # the stamp stays zero: no "goals accepted before"
        request = graph.build_message(CANCEL_SERVICE + "_Request", {"goal_info": info})
        return client.call(request, timeout)
    finally:
        client.close()


class GoalRun:
    """One `action send-goal`: the DDS backend's steps and lines, on rclpy's ActionClient."""

    def __init__(
        self,
        graph: RclpyGraph,
        name: str,
        kind: str | None,
        value: Any,
        timeout: float | None,
        w: GoalWatcher,
    ) -> None:
        self.graph = graph
        self.action = resolve(name)
        self.timeout = timeout
        self.watcher = w
        if kind is None:
            found = next((a for a in graph.actions() if a.name == self.action), None)
            if found is None:
                raise RostoolError(
                    f"unknown action {self.action}: no server announces it (see `rostool action list`); "
                    "give its TYPE after the name to wait for a server"
                )
            kind = found.type
        self.types, self.cls = register_action(graph, kind)
        self.goal = self._build_goal(value)  # bad values fail here, before anything is sent
        self.feedback: queue.SimpleQueue[Any] = queue.SimpleQueue()

    def _build_goal(self, value: Any) -> Any:
        from rostool.interfaces.fill import FillError, build_message

        goal_type = self.types.part("Goal")
        types = self.graph.types
        try:
            return build_message(types.store, goal_type, types.with_defaults(goal_type, value))
        except FillError as err:
            raise RostoolError(f"{err} (the goal of {self.types.name})") from err

    def _on_feedback(self, message: Any) -> None:  # the executor's thread: handed to the main thread
        self.feedback.put(rtypes.from_rclpy(self.graph.types, message, self.types.feedback_message).feedback)

    def _drain(self) -> None:
        while True:
            try:
                feedback = self.feedback.get_nowait()
            except queue.Empty:
                return
            self.watcher.event(GoalEvent("feedback", 2, feedback))

    def run(self) -> GoalOutcome:
        from rclpy.action import ActionClient
        from unique_identifier_msgs.msg import UUID

        graph, watcher, action = self.graph, self.watcher, self.action
        client = ActionClient(graph.node, self.cls, action)
        started = time.monotonic()
        limit = self.timeout if self.timeout is not None else float("inf")
        if not _server_ready(client, started + min(limit, 1.0)):
            watcher.waiting("Waiting for an action server to become available...")
            if not _server_ready(client, started + limit):
                raise RostoolError(f"no action server for {action} matched within {self.timeout:g} s")
        goal_id = uuid.uuid4().bytes
        hex_id = goal_id.hex()
        goal = rtypes.to_rclpy(graph.types, self.goal, self.types.part("Goal"), self.cls.Goal)
        result_future: Any = None
        # One try from the moment the goal may reach the server: it must not run on after a Ctrl+C
        try:
            sent = client.send_goal_async(goal, self._on_feedback, UUID(uuid=list(goal_id)))
            if not _wait(sent, started + limit):
                raise GoalTimeout(f"goal {hex_id} got no result within {self.timeout:g} s; canceled it")
            handle = sent.result()
            watcher.sent(hex_id, self.goal, bool(handle.accepted))
            if not handle.accepted:
                return GoalOutcome(hex_id, None)
            result_future = handle.get_result_async()
            done = threading.Event()
            result_future.add_done_callback(lambda _f: done.set())
            while not done.wait(0.02):
                self._drain()
                if time.monotonic() - started > limit and not done.is_set():
                    raise GoalTimeout(f"goal {hex_id} got no result within {self.timeout:g} s; canceled it")
        except (KeyboardInterrupt, GoalTimeout):
            watcher.canceling(hex_id)
            if result_future is None:  # maybe never sent, or not accepted: cancel what the server may have
                with contextlib.suppress(RostoolError):
                    _cancel(graph, action, goal_id, CANCEL_WAIT)
                raise
            response = _cancel(graph, action, goal_id, 5.0)
            if response.return_code != 0 or not response.goals_canceling:
                why = CANCEL_ERRORS.get(response.return_code, f"return code {response.return_code}")
                raise RostoolError(f"canceling goal {hex_id} failed: {why}") from None
            if _wait(result_future, time.monotonic() + CANCEL_WAIT):  # how the goal ended
                final = self._result(result_future)
                watcher.event(GoalEvent("result", int(final.status), final.result))
            raise
        self._drain()  # feedback that came with the result
        final = self._result(result_future)
        watcher.event(GoalEvent("result", int(final.status), final.result))
        return GoalOutcome(hex_id, int(final.status), final.result)

    def _result(self, future: Any) -> Any:
        if future.exception() is not None:
            raise RostoolError(f"getting the result of a goal of {self.action} failed: {future.exception()}")
        response = future.result()
        return rtypes.from_rclpy(self.graph.types, response, self.types.get_result + "_Response")
