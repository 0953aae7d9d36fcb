"""What several action verbs share: -c, and the refusal of ros2 action's flags on a ROS 1 graph."""

from __future__ import annotations

import click

from rostool.errors import RostoolError
from rostool.graph.base import Graph

count_option = click.option(
    "-c", "--count-actions", "--count", "count", is_flag=True, help="Only the number of actions."
)


def ros2_flags(graph: Graph, verb: str, **given: bool) -> None:
    used = [name for name, value in given.items() if value]
    if used and graph.style != "ros2":
        flags = ", ".join("--" + name.replace("_", "-") for name in used)
        raise RostoolError(f"action {verb} {flags}: ros2 action forms; under ROS 1 see `rostool action info`")
