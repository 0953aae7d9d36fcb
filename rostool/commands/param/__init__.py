"""`rostool param`: list, get, set, delete, dump, load (rosparam's forms, typed YAML values); on ROS 2 also
describe, in ros2 param's forms and output (NODE first, --include-hidden-nodes, --timeout); each verb in its
own module."""

from __future__ import annotations

import click

from rostool.commands._common import ExtensibleGroup

_VERBS = {
    "list": "list:list_params", "get": "get:get", "set": "set:set_", "describe": "describe:describe",
    "delete": "delete:delete", "dump": "dump:dump", "load": "load:load",
}  # fmt: skip


@click.group(cls=ExtensibleGroup, extra={verb: f"{__name__}.{spec}" for verb, spec in _VERBS.items()})
def param() -> None:
    """Read and write the parameter server (like rosparam).

    \b
    Examples:
      rostool param set /wheel_radius 0.05
      rostool param get /wheel_radius
      rostool param dump params.yaml
      rostool param load params.yaml
      rostool --ros2 param get /talker use_sim_time     # ROS 2: NODE then PARAM
      rostool --ros2 param dump /talker > talker.yaml

    Flags and output follow the selected ROS version: rosparam's under ROS 1, ros2 param's under ROS 2 (NODE
    first, --include-hidden-nodes, --timeout). --json works in both. --spin-time S waits S seconds for
    discovery when no graph daemon answers, as ros2cli's does; -s/--use-sim-time is accepted and ignored.
    """
