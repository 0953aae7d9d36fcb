"""`rostool topic type`: a topic's type alone (rostopic type, ros2 topic type)."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.commands.topic._options import include_hidden_option
from rostool.errors import RostoolError


@click.command("type")
@click.argument("name")
@include_hidden_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def type_(ctx: click.Context, name: str, include_hidden: bool) -> None:
    """Print only the type of a topic (for scripts).

    \b
    Example:
      rostool topic type /hello_world      # std_msgs/String
    """
    from rostool.interfaces.names import hidden_name

    with live_graph(ctx) as graph:
        found = graph.topic_type(name)
        if graph.style == "ros2" and not include_hidden and hidden_name(graph.resolve(name)):
            found = None
    if found is None:
        raise RostoolError(f"unknown topic {name}: it has no publishers or subscribers")
    click.echo(found)
