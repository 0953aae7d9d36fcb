"""ROS 2 action types, derived as rosidl_parser's `Action` derives them (definitions.py): rosbags' stores
hold action_msgs and unique_identifier_msgs but no action types, so the goal, result and feedback come
from .action text: rostool's own few, or .action files in the interface sources."""

from __future__ import annotations

from dataclasses import dataclass

from rostool.errors import RostoolError
from rostool.interfaces.definitions import action_types
from rostool.interfaces.ros2_types import Ros2Types

ACTION_DEFINITIONS: dict[str, str] = {
    "example_interfaces/action/Fibonacci": "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n",
    "test_msgs/action/Fibonacci": "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n",
}


def action_store_name(action_type: str) -> str:
    """`pkg/Name` or `pkg/action/Name` -> `pkg/action/Name`."""
    parts = action_type.strip().strip("/").split("/")
    if len(parts) == 2 or (len(parts) == 3 and parts[1] == "action"):
        return f"{parts[0]}/action/{parts[-1]}"
    raise RostoolError(f"bad action type {action_type!r}: use pkg/action/Name (or pkg/Name)")


@dataclass(frozen=True)
class ActionTypes:
    """Store names of one action's types."""

    name: str  # pkg/action/Name

    def part(self, suffix: str) -> str:
        return f"{self.name}_{suffix}"

    @property
    def send_goal(self) -> str:
        return self.part("SendGoal")

    @property
    def get_result(self) -> str:
        return self.part("GetResult")

    @property
    def feedback_message(self) -> str:
        return self.part("FeedbackMessage")


def register_action(types: Ros2Types, action_type: str, text: str | None = None) -> ActionTypes:
    """Make an action's goal, result, feedback and derived service/message types known to the store.

    Looked up in order: the store, `text`, rostool's built-in definitions, then .action source files."""
    name = action_store_name(action_type)
    found = ActionTypes(name)
    if types.in_store(found.feedback_message):
        return found
    text = text if text is not None else ACTION_DEFINITIONS.get(name)
    if text is None:
        if types.knows(found.feedback_message):
            return found
        raise types.unknown("action", name, sorted(ACTION_DEFINITIONS))
    types.register(action_types(name, text, f"the definition of {name}"))
    return found
