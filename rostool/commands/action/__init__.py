"""`rostool action`: list, info, type, find, show, send-goal, cancel (actionlib over topics, ROS 1); on ROS 2
list, info and send-goal in ros2 action's forms and output, and cancel over ACTION/_action/cancel_goal; each
verb in its own module."""

from __future__ import annotations

import click

from rostool.commands._common import ExtensibleGroup

_VERBS = {
    "list": "list:list_actions", "info": "info:info", "type": "type:type_", "find": "find:find",
    "show": "show:show", "send-goal": "send_goal:send_goal", "cancel": "cancel:cancel",
    "send_goal": "send_goal:send_goal",  # ros2 action's spelling
}  # fmt: skip


@click.group(cls=ExtensibleGroup, extra={verb: f"{__name__}.{spec}" for verb, spec in _VERBS.items()})
def action() -> None:
    """Use actionlib actions (ROS 1) and ROS 2 actions: list servers, send goals and follow them, cancel.

    Goal, result and feedback types come from .action files in source trees (--interfaces,
    ROS_PACKAGE_PATH, the current workspace; on ROS 2 also AMENT_PREFIX_PATH) or the built-in types: no
    catkin or colcon build needed.

    \b
    Examples:
      rostool action list
      rostool action info /navigate_2d_action
      rostool action send-goal /navigate_2d_action "{point: {x: 1.0, y: 2.0}}" --feedback
      rostool action cancel /navigate_2d_action
      rostool --ros2 action send-goal /fibonacci example_interfaces/action/Fibonacci "{order: 5}" --feedback
      rostool --ros2 action cancel /fibonacci
      rostool --ros2 action send_goal -f /fibonacci test_msgs/action/Fibonacci "{order: 5}"

    Flags and output follow the selected ROS version: actionlib's tools' under ROS 1, ros2 action's under
    ROS 2 (send_goal is send-goal). --json works in both. --spin-time S waits S seconds for discovery when
    no graph daemon answers, as ros2cli's does; -s/--use-sim-time is accepted and ignored.
    """
