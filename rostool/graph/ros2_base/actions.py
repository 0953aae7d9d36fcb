"""ROS 2 actions as both transports see them (rcl_action's layout, rcl_action/names.c): an action
`/fibonacci` is the services `/fibonacci/_action/send_goal`, `get_result` and `cancel_goal` and the topics
`feedback` and `status`. Listing them, canceling goals, and the lines and events of a goal's run are the
same over either transport; following a goal is each transport's (its action client)."""

from __future__ import annotations

import uuid
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.base import ActionSummary, CancelingGoal, GoalEvent, GoalOutcome

if TYPE_CHECKING:
    from rostool.graph.ros2_base.transport import Ros2Host

ACTION_INFIX = "/_action/"
CANCEL_SERVICE = "action_msgs/srv/CancelGoal"
CANCEL_WAIT = 3.0  # after a cancel, how long to wait for the goal's final result
WAITING = "Waiting for an action server to become available..."

# action_msgs/msg/GoalStatus
STATUS_NAMES = {0: "UNKNOWN", 1: "ACCEPTED", 2: "EXECUTING", 3: "CANCELING", 4: "SUCCEEDED", 5: "CANCELED",
                6: "ABORTED"}  # fmt: skip
EXECUTING = 2
SUCCEEDED = 4
CANCEL_ERRORS = {1: "the server rejected the cancel request", 2: "the server does not know the goal",
                 3: "the goal already finished"}  # fmt: skip


class GoalTimeout(RostoolError):
    pass


def stop_if_asked(watcher: Any) -> None:
    """Raise KeyboardInterrupt, as Ctrl+C does, when the watcher's owner asked for the goal's cancel (the
    graph daemon running a goal for a verb whose user pressed Ctrl+C: `cancel_asked`, an Event); each
    backend's wait loops call it, so the cancel takes the direct Ctrl+C's way at a point where the run
    holds nothing."""
    asked = getattr(watcher, "cancel_asked", None)
    if asked is not None and asked.is_set():
        raise KeyboardInterrupt


def status_name(status: int) -> str:
    return STATUS_NAMES.get(status, f"status {status}")


def feedback_event(message: Any) -> GoalEvent:
    return GoalEvent("feedback", EXECUTING, status_name(EXECUTING), message)


def result_event(status: int, message: Any) -> GoalEvent:
    return GoalEvent("result", status, status_name(status), message)


def outcome(goal_id: str, status: int | None, result: Any = None) -> GoalOutcome:
    return GoalOutcome(goal_id, status, result, succeeded=status == SUCCEEDED)


def split_action_service(service: str) -> tuple[str, str] | None:
    """`/fibonacci/_action/send_goal` -> ('/fibonacci', 'send_goal'); None for other services."""
    action, infix, rest = service.rpartition(ACTION_INFIX)
    return (action, rest) if infix and action and "/" not in rest else None


def list_actions(graph: Ros2Host, nodes: bool = False) -> list[ActionSummary]:
    """Actions with a server (a `ACTION/_action/send_goal` service), with their clients (their node names
    complete only with `nodes`)."""
    found: dict[str, ActionSummary] = {}
    for name, type_, servers, clients in graph.service_endpoints(nodes):
        split = split_action_service(name)
        if split is None or split[1] != "send_goal":
            continue
        found[split[0]] = ActionSummary(split[0], type_.removesuffix("_SendGoal"), servers, clients)
    return [found[name] for name in sorted(found)]


def action_type(graph: Ros2Host, action: str, kind: str | None) -> str:
    """The type given, else the one the action's server announces."""
    if kind is not None:
        return kind
    found = next((a for a in list_actions(graph) if a.name == action), None)
    if found is None:
        raise RostoolError(
            f"unknown action {action}: no server announces it (see `rostool action list`); "
            "give its TYPE after the name to wait for a server"
        )
    return found.type


def parse_goal_id(text: str) -> bytes:
    """A goal id as send-goal prints it (32 hex digits), dashed UUID spellings too."""
    try:
        return uuid.UUID(text.strip()).bytes
    except ValueError:
        raise RostoolError(
            f"bad goal id {text!r}: give the 32 hex digits `rostool action send-goal` printed"
        ) from None


def cancel(graph: Ros2Host, action: str, goal_id: bytes, timeout: float) -> Any:
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


def cancel_goals(
    graph: Ros2Host, name: str, goal_id: str | None, timeout: float = 5.0
) -> list[CancelingGoal]:
    """Ask the server of action `name` to cancel one goal, or every goal when `goal_id` is None (a zero goal
    id and a zero stamp: action_msgs/srv/CancelGoal's "cancel all"); the goals it is canceling."""
    action = graph.resolve(name)
    wanted = parse_goal_id(goal_id) if goal_id is not None else bytes(16)
    response = cancel(graph, action, wanted, timeout)
    what = f"goal {wanted.hex()}" if goal_id is not None else "every goal"
    if response.return_code != 0:
        why = CANCEL_ERRORS.get(response.return_code, f"return code {response.return_code}")
        raise RostoolError(f"canceling {what} of {action} failed: {why}")
    return [CancelingGoal(bytes(g.goal_id.uuid).hex(), g.stamp) for g in response.goals_canceling]


def check_canceled(response: Any, hex_id: str) -> None:
    """A send-goal's own cancel (timeout, Ctrl+C) must have been taken."""
    if response.return_code != 0 or not response.goals_canceling:
        why = CANCEL_ERRORS.get(response.return_code, f"return code {response.return_code}")
        raise RostoolError(f"canceling goal {hex_id} failed: {why}") from None
