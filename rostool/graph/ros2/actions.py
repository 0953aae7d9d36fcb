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
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.base import ActionSummary
from rostool.graph.ros2 import dds
from rostool.graph.ros2.names import resolve, topic_to_dds
from rostool.graph.ros2.services import ServiceClient, remote_writer_known
from rostool.interfaces.ros2_action import register_action

if TYPE_CHECKING:
    from rostool.graph.ros2.graph import Ros2Graph, Session

ACTION_INFIX = "/_action/"
FEEDBACK_QOS = dds.PROFILES["default"]
STATUS_QOS = dds.QosProfile("reliable", "transient_local", 1)
STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
CANCEL_SERVICE = "action_msgs/srv/CancelGoal"
UUID_TYPE = "unique_identifier_msgs/msg/UUID"
_ANY_SAMPLE = 0x7F
CANCEL_WAIT = 3.0  # after a cancel, how long to wait for the goal's final result

# action_msgs/msg/GoalStatus
STATUS_NAMES = {0: "UNKNOWN", 1: "ACCEPTED", 2: "EXECUTING", 3: "CANCELING", 4: "SUCCEEDED", 5: "CANCELED",
                6: "ABORTED"}  # fmt: skip
SUCCEEDED = 4
CANCEL_ERRORS = {1: "the server rejected the cancel request", 2: "the server does not know the goal",
                 3: "the goal already finished"}  # fmt: skip


def status_name(status: int) -> str:
    return STATUS_NAMES.get(status, f"status {status}")


def split_action_service(service: str) -> tuple[str, str] | None:
    """`/fibonacci/_action/send_goal` -> ('/fibonacci', 'send_goal'); None for other services."""
    action, infix, rest = service.rpartition(ACTION_INFIX)
    return (action, rest) if infix and action and "/" not in rest else None


def list_actions(graph: Ros2Graph, nodes: bool = False) -> list[ActionSummary]:
    """Actions with a server (a reader of `ACTION/_action/send_goal` requests), with clients (their node
    names complete only with `nodes`)."""
    found: dict[str, ActionSummary] = {}
    for name, type_, servers, clients in graph.service_endpoints(nodes):
        split = split_action_service(name)
        if split is None or split[1] != "send_goal":
            continue
        action_type = type_.removesuffix("_SendGoal")
        found[split[0]] = ActionSummary(split[0], action_type, servers, clients)
    return [found[name] for name in sorted(found)]


@dataclass
class GoalEvent:
    kind: str  # "feedback" or "result"
    status: int
    message: Any = None  # the feedback or result message
    text: str = ""

    @property
    def status_name(self) -> str:
        return status_name(self.status)


@dataclass
class GoalOutcome:
    goal_id: str
    status: int | None
    result: Any = None
    canceled: bool = False

    @property
    def succeeded(self) -> bool:
        return self.status == SUCCEEDED


class GoalTimeout(RostoolError):
    pass


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
    graph: Ros2Graph,
    name: str,
    type_name: str | None,
    value: Any,
    timeout: float | None = None,
    on_event: Callable[[GoalEvent], None] | None = None,
    on_sent: Callable[[str, Any, bool], None] | None = None,
    on_waiting: Callable[[str], None] | None = None,
    on_cancel: Callable[[str], None] | None = None,
) -> GoalOutcome:
    """`ros2 action send_goal`: the goal is canceled first on timeout or Ctrl+C."""
    action = resolve(name)
    if type_name is None:
        found = next((a for a in list_actions(graph) if a.name == action), None)
        if found is None:
            raise RostoolError(
                f"unknown action {action}: no server announces it (see `rostool action list`); "
                "give its TYPE after the name to wait for a server"
            )
        type_name = found.type
    client = ActionClient(graph.session, action, type_name)
    goal = client.build_goal(value)  # bad values fail here, before anything is sent
    started = time.monotonic()
    limit = timeout if timeout is not None else float("inf")
    if not client.wait_for_server(min(limit, 1.0)):
        if on_waiting is not None:
            on_waiting("Waiting for an action server to become available...")
        if not client.wait_for_server(max(limit - (time.monotonic() - started), 0.0)):
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
        finally:
            finished.set()

    fetching = False
    # One try from the moment the goal may reach the server: it must not run on after a Ctrl+C, even one
    # that comes before the server's answer (it may have accepted the goal already)
    try:
        _, accepted = client.send(goal, max(limit - (time.monotonic() - started), 0.01), goal_id)
        if on_sent is not None:
            on_sent(hex_id, goal, accepted)
        if not accepted:
            return GoalOutcome(hex_id, None)
        threading.Thread(target=fetch, name=f"result of {action}", daemon=True).start()
        fetching = True
        while not finished.wait(0.02):
            for feedback in client.take_feedback(goal_id):
                if on_event is not None:
                    on_event(GoalEvent("feedback", 2, feedback))
            if time.monotonic() - started > limit and not finished.is_set():
                raise GoalTimeout(f"goal {hex_id} got no result within {timeout:g} s; canceled it")
    except (KeyboardInterrupt, GoalTimeout):
        if on_cancel is not None:
            on_cancel(hex_id)
        if not fetching:  # maybe never sent, or not accepted: cancel what the server may have
            with contextlib.suppress(RostoolError):
                client.cancel(goal_id, CANCEL_WAIT)
            raise
        response = client.cancel(goal_id)
        if response.return_code != 0 or not response.goals_canceling:
            why = CANCEL_ERRORS.get(response.return_code, f"return code {response.return_code}")
            raise RostoolError(f"canceling goal {hex_id} failed: {why}") from None
        finished.wait(CANCEL_WAIT)  # the server's answer to get_result says how the goal ended
        final = box.get("response")
        if final is not None and on_event is not None:
            on_event(GoalEvent("result", int(final.status), final.result))
        raise
    if "error" in box:
        raise box["error"]
    response = box["response"]
    for feedback in client.take_feedback(goal_id):  # feedback that came with the result
        if on_event is not None:
            on_event(GoalEvent("feedback", 2, feedback))
    if on_event is not None:
        on_event(GoalEvent("result", int(response.status), response.result))
    return GoalOutcome(hex_id, int(response.status), response.result)


def parse_goal_id(text: str) -> bytes:
    """A goal id as send-goal prints it (32 hex digits), dashed UUID spellings too."""
    try:
        return uuid.UUID(text.strip()).bytes
    except ValueError:
        raise RostoolError(
            f"bad goal id {text!r}: give the 32 hex digits `rostool action send-goal` printed"
        ) from None


@dataclass
class CancelingGoal:
    goal_id: str  # hex
    stamp: Any  # builtin_interfaces/msg/Time: when the server accepted the goal


def cancel_goals(
    graph: Ros2Graph, name: str, goal_id: str | None, timeout: float = 5.0
) -> list[CancelingGoal]:
    """Ask the server of action `name` to cancel one goal, or every goal when `goal_id` is None (a zero goal
    id and a zero stamp: action_msgs/srv/CancelGoal's "cancel all"); the goals it is canceling."""
    from rostool.interfaces.fill import build_message

    action = resolve(name)
    wanted = parse_goal_id(goal_id) if goal_id is not None else bytes(16)
    client = ServiceClient(graph.session, action + ACTION_INFIX + "cancel_goal", CANCEL_SERVICE)
    if not client.wait_for_server(timeout):
        raise RostoolError(
            f"no action server for {action} matched within {timeout:g} s (see `rostool action list`)"
        )
    info = {"goal_id": {"uuid": list(wanted)}}  # the stamp stays zero: no "goals accepted before"
    request = build_message(graph.types.store, CANCEL_SERVICE + "_Request", {"goal_info": info})
    response = client.call(request, timeout)
    what = f"goal {wanted.hex()}" if goal_id is not None else "every goal"
    if response.return_code != 0:
        why = CANCEL_ERRORS.get(response.return_code, f"return code {response.return_code}")
        raise RostoolError(f"canceling {what} of {action} failed: {why}")
    return [CancelingGoal(bytes(g.goal_id.uuid).hex(), g.stamp) for g in response.goals_canceling]
