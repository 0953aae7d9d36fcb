"""`rostool node`: list, info, ping, kill (rosnode's forms under ROS 1, ros2 node's under ROS 2); each verb in
its own module."""

from __future__ import annotations

import click

from rostool.commands._common import ExtensibleGroup

_VERBS = {"list": "list:list_nodes", "info": "info:info", "ping": "ping:ping", "kill": "kill:kill"}


@click.group(cls=ExtensibleGroup, extra={verb: f"{__name__}.{spec}" for verb, spec in _VERBS.items()})
def node() -> None:
    """Inspect and stop nodes (like rosnode, or ros2 node).

    Flags and output follow the selected ROS version (--ros1/--ros2, ROS_VERSION, detection): rosnode's
    forms under ROS 1, ros2 node's under ROS 2; --json works in both. --spin-time S waits S seconds for
    discovery when no graph daemon answers, as ros2cli's does; -s/--use-sim-time is accepted and ignored.

    \b
    Examples:
      rostool node list
      rostool node info /hello_world_pub_node
      rostool node ping /hello_world_pub_node -c 3
      rostool node kill /hello_world_pub_node
    """
