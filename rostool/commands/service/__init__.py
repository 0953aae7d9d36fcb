"""`rostool service`: list, type, info, uri, node, args, find, echo, call (rosservice's forms and output;
on ROS 2 list, type, info, find, echo and call in ros2 service's forms and output); a module per verb."""

from __future__ import annotations

import click

from rostool.commands._common import ExtensibleGroup

_VERBS = {
    "list": "list:list_services", "type": "type:type_", "uri": "lookups:uri", "node": "lookups:node",
    "args": "lookups:args", "info": "info:info", "find": "find:find", "echo": "echo:echo",
    "call": "call:call",
}  # fmt: skip


@click.group(cls=ExtensibleGroup, extra={verb: f"{__name__}.{spec}" for verb, spec in _VERBS.items()})
def service() -> None:
    """Inspect and call services (like rosservice; on ROS 2 like ros2 service). Types come from the service
    itself and from .srv files in source trees (--interfaces, ROS_PACKAGE_PATH, the current workspace; on
    ROS 2 also AMENT_PREFIX_PATH): no build needed.

    \b
    Examples:
      rostool service list
      rostool service type /sum_two_ints
      rostool service call /sum_two_ints 7 8
      rostool service call /sum_two_ints "{a: 7, b: 8}" --json
      rostool --ros2 service call /add_two_ints example_interfaces/srv/AddTwoInts "{a: 1, b: 2}"
      rostool --ros2 service info /add_two_ints
      rostool --ros2 service echo /add_two_ints      # needs the service's introspection on

    Flags and output follow the selected ROS version: rosservice's under ROS 1, ros2 service's under ROS 2.
    --json works in both. --spin-time S waits S seconds for discovery when no graph daemon answers, as
    ros2cli's does; -s/--use-sim-time is accepted and ignored.
    """
