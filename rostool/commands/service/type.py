"""`rostool service type`: a service's type (rosservice type asks the service, ros2 service type the
graph)."""

from __future__ import annotations

import click

from rostool.commands._common import echo_announced_types, ignored_ros2_options, live_graph


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
            announced = [(n, t) for n, t, _ in graph.services()]
            echo_announced_types("service", graph.resolve(name), announced)
            return
        click.echo(graph.service_type(name))
