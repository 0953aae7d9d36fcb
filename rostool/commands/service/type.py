"""`rostool service type`: a service's type (rosservice type asks the service, ros2 service type the
graph)."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.errors import RostoolError


@click.command("type")
@click.argument("name", metavar="SERVICE")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def type_(ctx: click.Context, name: str) -> None:
    """Print the type of a service (asked from the service itself).

    \b
    Examples:
      rostool service type /sum_two_ints      # sum_two_numbers/SumTwoInts
      rostool --ros2 service type /add_two_ints   # example_interfaces/srv/AddTwoInts
    """
    with live_graph(ctx) as graph:
        if graph.style == "ros2":  # as ros2 service type: the announced type(s), or nothing and exit 1
            resolved = graph.resolve(name)
            types = sorted({t for n, t, _ in graph.services() if n == resolved and t})
            if not types:
                raise RostoolError(
                    f"unknown service {resolved}: no server announces it (`rostool service list`)"
                )
            click.echo("\n".join(types))
            return
        click.echo(graph.service_type(name))
