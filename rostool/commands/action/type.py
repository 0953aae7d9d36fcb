"""`rostool action type`: an action's type (ros2 action type)."""

from __future__ import annotations

import click

from rostool.commands._common import echo_announced_types, ignored_ros2_options, live_graph


@click.command("type")
@click.argument("name", metavar="ACTION")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def type_(ctx: click.Context, name: str) -> None:
    """Print an action's type (ros2 action type; nothing and exit 1 when no server announces it).

    \b
    Examples:
      rostool --ros2 action type /fibonacci       # test_msgs/action/Fibonacci
      rostool action type /navigate_2d_action
    """
    with live_graph(ctx) as graph:
        resolved = graph.resolve(name)
        announced = [(a.name, a.type) for a in graph.actions()]
    echo_announced_types("action", resolved, announced)
