"""`rostool action find`: the actions of a type (ros2 action find)."""

from __future__ import annotations

import click

from rostool.commands._common import echo_names, ignored_ros2_options, live_graph
from rostool.commands.action._options import count_option


@click.command("find")
@click.argument("type_name", metavar="TYPE")
@count_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def find(ctx: click.Context, type_name: str, count: bool) -> None:
    """List the actions of type TYPE (ros2 action find).

    \b
    Examples:
      rostool --ros2 action find test_msgs/action/Fibonacci
      rostool --ros2 action find -c test_msgs/action/Fibonacci
    """
    from rostool.interfaces.names import to_store_name

    with live_graph(ctx) as graph:
        wanted = {type_name, to_store_name(type_name, "action")}
        names = sorted(a.name for a in graph.actions() if a.type in wanted)
    echo_names(names, count)
