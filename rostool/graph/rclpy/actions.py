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
from rostool.graph.ros2_base.actions import (
    CANCEL_WAIT,
    WAITING,
    GoalTimeout,
    action_type,
    cancel,
    check_canceled,
    feedback_event,
    outcome,
    result_event,
    stop_if_asked,
)
from rostool.graph.ros2_base.names import resolve
from rostool.interfaces import ros2_action
from rostool.interfaces.ros2_action import ActionTypes

if TYPE_CHECKING:
    from rostool.graph.base import GoalOutcome, GoalWatcher
    from rostool.graph.rclpy.host import RclpyHost


def register_action(graph: RclpyHost, action_type: str) -> tuple[ActionTypes, Any]:
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


def _wait(future: Any, deadline: float, watcher: Any = None) -> bool:
    """Wait for an rclpy future until `deadline` (monotonic); whether it is done. A cancel the watcher's
    owner asked for meanwhile raises KeyboardInterrupt (`stop_if_asked`)."""
    done = threading.Event()
    future.add_done_callback(lambda _f: done.set())
    while not done.wait(0.02):
        stop_if_asked(watcher)
        if time.monotonic() >= deadline:
            return False
    return True


def _value(task: Any) -> Any:
    """A done executor task's value, its exception raised here."""
    if task.exception() is not None:
        raise task.exception()
    return task.result()


def _server_ready(client: Any, deadline: float, watcher: Any = None) -> bool:
    while not client.server_is_ready():
        stop_if_asked(watcher)
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.02)
    return True


class GoalRun:
    """One `action send-goal`: the DDS backend's steps and lines, on rclpy's ActionClient."""

    def __init__(
        self,
        graph: RclpyHost,
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
        self.types, self.cls = register_action(graph, action_type(graph, self.action, kind))
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
            self.watcher.event(feedback_event(feedback))

    def run(self) -> GoalOutcome:
        from rclpy.action import ActionClient

        graph, action = self.graph, self.action
        client = ActionClient(graph.node, self.cls, action)
        try:
            return self._run(client)
        finally:
            # destroyed on the executor's thread, between two of its takes: a long-lived graph (the
            # daemon's, sending goals for verbs) would otherwise keep every goal's client
            with contextlib.suppress(Exception):  # the context is shut down already: so is the client
                graph.context.on_executor(client.destroy)

    def _run(self, client: Any) -> GoalOutcome:
        from unique_identifier_msgs.msg import UUID

        graph, watcher, action = self.graph, self.watcher, self.action
        started = time.monotonic()
        limit = self.timeout if self.timeout is not None else float("inf")
        if not _server_ready(client, started + min(limit, 1.0), watcher):
            watcher.waiting(WAITING)
            if not _server_ready(client, started + limit, watcher):
                raise RostoolError(f"no action server for {action} matched within {self.timeout:g} s")
        goal_id = uuid.uuid4().bytes
        hex_id = goal_id.hex()
        goal = rtypes.to_rclpy(graph.types, self.goal, self.types.part("Goal"), self.cls.Goal)
        result_future: Any = None
        # One try from the moment the goal may reach the server: it must not run on after a Ctrl+C
        try:
            # On the executor's thread: Jazzy's ActionClient registers a request's future only after
            # sending it, and a reply taken in between is dropped (the goal then waits forever)
            sending = graph.context.on_executor(
                lambda: client.send_goal_async(goal, self._on_feedback, UUID(uuid=list(goal_id)))
            )
            if not _wait(sending, started + limit, watcher):
                raise GoalTimeout(f"goal {hex_id} got no result within {self.timeout:g} s; canceled it")
            sent = _value(sending)
            if not _wait(sent, started + limit, watcher):
                raise GoalTimeout(f"goal {hex_id} got no result within {self.timeout:g} s; canceled it")
            handle = sent.result()
            watcher.sent(hex_id, self.goal, bool(handle.accepted))
            if not handle.accepted:
                return outcome(hex_id, None)
            asking = graph.context.on_executor(handle.get_result_async)
            if not _wait(asking, started + limit, watcher):
                raise GoalTimeout(f"goal {hex_id} got no result within {self.timeout:g} s; canceled it")
            result_future = _value(asking)
            done = threading.Event()
            result_future.add_done_callback(lambda _f: done.set())
            while not done.wait(0.02):
                stop_if_asked(watcher)
                self._drain()
                if time.monotonic() - started > limit and not done.is_set():
                    raise GoalTimeout(f"goal {hex_id} got no result within {self.timeout:g} s; canceled it")
        except (KeyboardInterrupt, GoalTimeout):
            watcher.canceling(hex_id)
            if result_future is None:  # maybe never sent, or not accepted: cancel what the server may have
                with contextlib.suppress(RostoolError):
                    cancel(graph, action, goal_id, CANCEL_WAIT)
                raise
            check_canceled(cancel(graph, action, goal_id, 5.0), hex_id)
            if _wait(result_future, time.monotonic() + CANCEL_WAIT):  # how the goal ended
                final = self._result(result_future)
                watcher.event(result_event(int(final.status), final.result))
            raise
        self._drain()  # feedback that came with the result
        final = self._result(result_future)
        watcher.event(result_event(int(final.status), final.result))
        return outcome(hex_id, int(final.status), final.result)

    def _result(self, future: Any) -> Any:
        if future.exception() is not None:
            raise RostoolError(f"getting the result of a goal of {self.action} failed: {future.exception()}")
        response = future.result()
        return rtypes.from_rclpy(self.graph.types, response, self.types.get_result + "_Response")
