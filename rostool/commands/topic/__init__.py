"""`rostool topic`: list, info, type, find, echo, hz, bw, delay, pub, plot: rostopic's forms under ROS 1,
ros2 topic's under ROS 2 (the verbs choose by `graph.style`); each verb in its own module."""

from __future__ import annotations

import click

from rostool.commands._common import ExtensibleGroup

_VERBS = {
    "list": "list:list_topics", "info": "info:info", "type": "type:type_", "find": "find:find",
    "echo": "echo:echo", "hz": "hz:hz", "bw": "bw:bw", "delay": "delay:delay", "pub": "pub:pub",
    "plot": "plot:plot",
}  # fmt: skip


@click.group(cls=ExtensibleGroup, extra={verb: f"{__name__}.{spec}" for verb, spec in _VERBS.items()})
def topic() -> None:
    """Inspect and use topics (like rostopic, or ros2 topic).

    Flags and output follow the selected ROS version (--ros1/--ros2, ROS_VERSION, detection): rostopic's
    forms under ROS 1, ros2 topic's under ROS 2. rostool's extras (several --field, --json, --filter, --csv)
    work in both. --spin-time S waits S seconds for discovery when no graph daemon answers, as ros2cli's
    does; -s/--use-sim-time is accepted and ignored.

    \b
    Examples:
      rostool topic list -v
      rostool topic echo /hello_world -n 3
      rostool topic hz /hello_world
      rostool topic pub /chatter std_msgs/String "data: hi" -r 5
      rostool --ros2 topic list -t
      rostool --ros2 topic pub -t 3 /chatter std_msgs/msg/String "{data: hi}"
    """
