"""ROS 1 action types: the actionlib messages of an .action, and actionlib's goal status codes.

`X.action` (goal, result and feedback separated by `---` lines) becomes XGoal, XResult, XFeedback, the
XActionGoal/XActionResult/XActionFeedback wrappers (Header plus actionlib_msgs/GoalID or GoalStatus) and
XAction (msgspec.load_action_specs). The texts are genaction's own, so md5sums and message definitions
match catkin-built peers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rostool.interfaces.msgspec import ACTION_SUFFIXES, InterfaceError
from rostool.interfaces.names import to_store_name
from rostool.interfaces.ros1 import builtin_store

if TYPE_CHECKING:
    from pathlib import Path

    from rostool.interfaces.ros1 import Ros1Type
    from rostool.interfaces.sources import Interfaces

GOAL_STATUS_NAMES = (
    "PENDING", "ACTIVE", "PREEMPTED", "SUCCEEDED", "ABORTED",
    "REJECTED", "PREEMPTING", "RECALLING", "RECALLED", "LOST",
)  # fmt: skip
TERMINAL_STATUSES = frozenset({2, 3, 4, 5, 8, 9})
SUCCEEDED = 3


def status_name(code: int) -> str:
    return GOAL_STATUS_NAMES[code] if 0 <= code < len(GOAL_STATUS_NAMES) else f"UNKNOWN({code})"


@dataclass(frozen=True)
class ActionType:
    name: str  # pkg/X
    goal: Ros1Type
    result: Ros1Type
    feedback: Ros1Type
    action_goal: Ros1Type
    action_result: Ros1Type
    action_feedback: Ros1Type
    action: Ros1Type
    origin: str


def action_type_name(name: str, catalog: Interfaces | None = None) -> str:
    """`pkg/X` from `pkg/X`, `pkg/action/X` or `pkg/XAction` (the message genaction makes)."""
    parts = name.strip("/").split("/")
    if len(parts) == 3 and parts[1] in ("action", "msg"):
        parts = [parts[0], parts[2]]
    if len(parts) != 2 or not all(parts):
        raise InterfaceError(f"{name!r} is not an action type; write it as package/Type")
    package, short = parts
    for suffix in ("ActionGoal", "Action"):
        base = short[: -len(suffix)]
        if short.endswith(suffix) and base:
            if catalog is not None and catalog.find_file(package, "action", short) is not None:
                break
            short = base
            break
    return f"{package}/{short}"


def load_action(catalog: Interfaces, name: str) -> ActionType:
    """Action `pkg/X` from an .action file in the sources, else from the built-in message store."""
    name = action_type_name(name, catalog)
    return catalog.built("action", name, lambda path: _make_action(catalog, name, path))


def _make_action(catalog: Interfaces, name: str, path: Path | None) -> ActionType:
    if path is not None:
        origin = str(path)
    elif to_store_name(f"{name}ActionGoal") in builtin_store().fielddefs:
        origin = f"built-in {name}"
    else:
        raise catalog.not_found("action", name)
    goal, result, feedback, action_goal, action_result, action_feedback, wrapper = (
        catalog.message(f"{name}{suffix}") for suffix in _FIELD_ORDER
    )
    return ActionType(
        name, goal, result, feedback, action_goal, action_result, action_feedback, wrapper, origin
    )


_FIELD_ORDER = ("Goal", "Result", "Feedback", "ActionGoal", "ActionResult", "ActionFeedback", "Action")
assert set(_FIELD_ORDER) == set(ACTION_SUFFIXES)


def action_names(catalog: Interfaces) -> list[str]:
    """Actions from .action files, and the built-in ones (whose generated messages rosbags ships)."""
    names = set(catalog.source_names("action"))
    for store_name in builtin_store().fielddefs:
        if store_name.endswith("ActionGoal") and "/msg/" in store_name:
            package, _, short = store_name.partition("/msg/")
            names.add(f"{package}/{short[: -len('ActionGoal')]}")
    return sorted(names)
