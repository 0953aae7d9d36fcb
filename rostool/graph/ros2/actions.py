"""ROS 2 actions over DDS, as rcl_action lays them out (rcl_action/names.c, default_qos.h).

An action `/fibonacci` of type `pkg/action/Fibonacci` is three services and two topics:

- `/fibonacci/_action/send_goal` (`pkg/action/Fibonacci_SendGoal`: request `goal_id` + `goal`, response
  `accepted` + `stamp`), `/fibonacci/_action/get_result` (`Fibonacci_GetResult`: request `goal_id`, response
  `status` + `result`; the server answers when the goal is done) and `/fibonacci/_action/cancel_goal`
  (`action_msgs/srv/CancelGoal`);
- `/fibonacci/_action/feedback` (`Fibonacci_FeedbackMessage`: `goal_id` + `feedback`, default QoS) and
  `/fibonacci/_action/status` (`action_msgs/msg/GoalStatusArray`; reliable, transient_local, depth 1).

`goal_id` is a unique_identifier_msgs/UUID (16 random bytes the client picks). The derived types are built
the way rosidl_parser's `Action` derives them (definitions.py); rosbags' stores hold action_msgs and
unique_identifier_msgs but no action types, so the goal, result and feedback come from .action text:
rostool's own few, or .action files in the interface sources.
"""

from __future__ import annotations

import contextlib
import threading
import time
import uuid
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.ros2.services import ServiceClient, remote_writer_known
from rostool.graph.ros2_base.actions import (
    ACTION_INFIX,
    CANCEL_SERVICE,
    CANCEL_WAIT,
    WAITING,
    GoalTimeout,
    action_type,
    check_canceled,
    feedback_event,
    outcome,
    result_event,
    stop_if_asked,
)
from rostool.graph.ros2_base.names import resolve, topic_to_dds
from rostool.graph.ros2_base.qos import PROFILES, QosProfile
from rostool.interfaces.ros2_action import register_action

if TYPE_CHECKING:
    from collections.abc import Callable

    from rostool.graph.base import GoalOutcome, GoalWatcher
    from rostool.graph.ros2.session import Session
    from rostool.graph.ros2_base.transport import Ros2Host

FEEDBACK_QOS = PROFILES["default"]
STATUS_QOS = QosProfile("reliable", "transient_local", 1)
STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
UUID_TYPE = "unique_identifier_msgs/msg/UUID"
_ANY_SAMPLE = 0x7F


class ActionClient:
    """Sends goals to one action server, follows their feedback and result, cancels them."""

    def __init__(self, session: Session, action: str, action_type: str) -> None:
        self.action = resolve(action)
        self.types = register_action(session.types, action_type)
        self._store = session.types
        base = self.action + ACTION_INFIX
        self._send_goal = ServiceClient(session, base + "send_goal", self.types.send_goal)
        self._get_result = ServiceClient(session, base + "get_result", self.types.get_result)
        self._cancel = ServiceClient(session, base + "cancel_goal", CANCEL_SERVICE)
        self._session = session
        self._feedback_topic = topic_to_dds(base + "feedback")
        self._feedback: Any = None  # created once Cyclone knows the server's feedback writer

    def build_goal(self, value: Any) -> Any:
        from rostool.interfaces.fill import FillError, build_message

        try:
            goal_type = self.types.part("Goal")
            return build_message(self._store.store, goal_type, self._store.with_defaults(goal_type, value))
        except FillError as err:
            raise RostoolError(f"{err} (the goal of {self.types.name})") from err

    def wait_for_server(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        for client in (self._send_goal, self._get_result, self._cancel):
            if not client.wait_for_server(max(deadline - time.monotonic(), 0.0)):
                return False
        while self._feedback is None or self._feedback.get_subscription_matched_status().current_count == 0:
            if self._feedback is None and remote_writer_known(self._session, self._feedback_topic):
                # only now: a Fast DDS writer's first heartbeat must reach a reader Cyclone already
                # matched, or the first feedback is taken for history and dropped (see services.py)
                self._feedback = self._session.reader(
                    self._feedback_topic, self.types.feedback_message, FEEDBACK_QOS
                )
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    def send(self, goal: Any, timeout: float, goal_id: bytes | None = None) -> tuple[bytes, bool]:
        """Send a goal with `goal_id` (else a fresh UUID); (goal id, accepted)."""
        from rostool.interfaces.fill import build_message

        goal_id = goal_id or uuid.uuid4().bytes
        request = build_message(
            self._store.store, self.types.send_goal + "_Request", {"goal_id": {"uuid": list(goal_id)}}
        )
        request.goal = goal
        response = self._send_goal.call(request, timeout)
        return goal_id, bool(response.accepted)

    def result(self, goal_id: bytes, timeout: float) -> Any:
        """Ask for the goal's result; the server replies when the goal is done (status, result)."""
        from rostool.interfaces.fill import build_message

        request = build_message(
            self._store.store, self.types.get_result + "_Request", {"goal_id": {"uuid": list(goal_id)}}
        )
        return self._get_result.call(request, timeout, forever=True)

    def cancel(self, goal_id: bytes, timeout: float = 5.0) -> Any:
        from rostool.interfaces.fill import build_message

        info = {"goal_id": {"uuid": list(goal_id)}}  # a zero stamp: this goal only
        request = build_message(self._store.store, CANCEL_SERVICE + "_Request", {"goal_info": info})
        return self._cancel.call(request, timeout)

    def close(self) -> None:
        """Delete its service clients and feedback reader: a long-lived graph (the daemon's, sending goals
        for verbs) would otherwise keep every goal's endpoints until it ends."""
        for client in (self._send_goal, self._get_result, self._cancel):
            client.close()
        feedback, self._feedback = self._feedback, None
        if feedback is not None:
            self._session.drop(feedback)

    def take_feedback(self, goal_id: bytes) -> list[Any]:
        """Feedback messages for `goal_id` received since the last call."""
        from cyclonedds._clayer import ddspy_take  # type: ignore[import-not-found]

        found: list[Any] = []
        if self._feedback is None:
            return found
        samples = ddspy_take(self._feedback._ref, _ANY_SAMPLE, 256)
        for data, info in [] if isinstance(samples, int) else samples:
            if not info.valid_data:
                continue
            message = self._store.deserialize(data, self.types.feedback_message)
            if bytes(message.goal_id.uuid) == goal_id:
                found.append(message.feedback)
        return found


def send_goal(
    graph: Ros2Host,
    session: Session,
    name: str,
    kind: str | None,
    value: Any,
    timeout: float | None,
    watcher: GoalWatcher,
) -> GoalOutcome:
    """`ros2 action send_goal` through `session`: the goal is canceled first on timeout or Ctrl+C."""
    action = resolve(name)
    client = ActionClient(session, action, action_type(graph, action, kind))
    # closed by the last of this call and its result thread (one still waiting after a cancel)
    users = _Users(client.close)
    try:
        return _send_goal(client, users, action, value, timeout, watcher)
    finally:
        users.release()


def _server_ready(client: ActionClient, deadline: float, watcher: GoalWatcher) -> bool:
    """`wait_for_server` until `deadline` (monotonic), in slices: a cancel asked meanwhile is noticed."""
    while not client.wait_for_server(min(max(deadline - time.monotonic(), 0.0), 0.1)):
        stop_if_asked(watcher)
        if time.monotonic() >= deadline:
            return False
    return True


class _Users:
    """Calls `close` once every user has released (a counted hold, for a thread that may outlive us)."""

    def __init__(self, close: Callable[[], None]) -> None:
        self._close = close
        self._count = 1
        self._lock = threading.Lock()

    def hold(self) -> None:
        with self._lock:
            self._count += 1

    def release(self) -> None:
        with self._lock:
            self._count -= 1
            last = self._count == 0
        if last:
            with contextlib.suppress(Exception):  # the participant is gone already: so are they
                self._close()


def _send_goal(
    client: ActionClient, users: _Users, action: str, value: Any, timeout: float | None, watcher: GoalWatcher
) -> GoalOutcome:
    goal = client.build_goal(value)  # bad values fail here, before anything is sent
    started = time.monotonic()
    limit = timeout if timeout is not None else float("inf")
    if not _server_ready(client, started + min(limit, 1.0), watcher):
        watcher.waiting(WAITING)
        if not _server_ready(client, started + limit, watcher):
            raise RostoolError(f"no action server for {action} matched within {timeout:g} s")
    goal_id = uuid.uuid4().bytes
    hex_id = goal_id.hex()
    box: dict[str, Any] = {}
    # An Event, not Thread.join: a join interrupted by Ctrl+C marks the thread finished (bpo-45274 fix)
    finished = threading.Event()

    def fetch() -> None:
        try:
            box["response"] = client.result(goal_id, float("inf"))
        except RostoolError as err:  # pragma: no cover - the server vanished
            box["error"] = err
        except Exception:  # its client closed under it (the graph closing): nothing to report
            pass
        finally:
            finished.set()
            users.release()

    fetching = False
    # One try from the moment the goal may reach the server: it must not run on after a Ctrl+C, even one
    # that comes before the server's answer (it may have accepted the goal already)
    try:
        _, accepted = client.send(goal, max(limit - (time.monotonic() - started), 0.01), goal_id)
        watcher.sent(hex_id, goal, accepted)
        if not accepted:
            return outcome(hex_id, None)
        users.hold()
        threading.Thread(target=fetch, name=f"result of {action}", daemon=True).start()
        fetching = True
        while not finished.wait(0.02):
            stop_if_asked(watcher)
            for feedback in client.take_feedback(goal_id):
                watcher.event(feedback_event(feedback))
            if time.monotonic() - started > limit and not finished.is_set():
                raise GoalTimeout(f"goal {hex_id} got no result within {timeout:g} s; canceled it")
    except (KeyboardInterrupt, GoalTimeout):
        watcher.canceling(hex_id)
        if not fetching:  # maybe never sent, or not accepted: cancel what the server may have
            with contextlib.suppress(RostoolError):
                client.cancel(goal_id, CANCEL_WAIT)
            raise
        check_canceled(client.cancel(goal_id), hex_id)
        finished.wait(CANCEL_WAIT)  # the server's answer to get_result says how the goal ended
        final = box.get("response")
        if final is not None:
            watcher.event(result_event(int(final.status), final.result))
        raise
    if "error" in box:
        raise box["error"]
    response = box["response"]
    for feedback in client.take_feedback(goal_id):  # feedback that came with the result
        watcher.event(feedback_event(feedback))
    watcher.event(result_event(int(response.status), response.result))
    return outcome(hex_id, int(response.status), response.result)
