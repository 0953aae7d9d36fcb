"""`rostool service find`: the services of a type (rosservice find, ros2 service find)."""

from __future__ import annotations

import click

from rostool.commands._common import echo_names, ignored_ros2_options, live_graph
from rostool.commands.service._options import count_option, hidden_services_option
from rostool.errors import RostoolError


@click.command("find")
@click.argument("type_name", metavar="TYPE")
@hidden_services_option
@count_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def find(ctx: click.Context, type_name: str, hidden: bool, count: bool) -> None:
    """List the services of type TYPE.

    \b
    Examples:
      rostool service find std_srvs/Trigger
      rostool --ros2 service find std_srvs/srv/SetBool -c
    """
    with live_graph(ctx) as graph:
        if graph.style == "ros1" and hidden:
            raise RostoolError("service find -a applies to ROS 2 graphs only")
        if graph.style == "ros2":
            from rostool.interfaces.names import hidden_name, to_store_name

            wanted = {type_name, to_store_name(type_name, "srv")}
            names = sorted(
                n for n, t, _ in graph.services() if t in wanted and (hidden or not hidden_name(n))
            )
        else:
            names = graph.find_services(type_name)
    echo_names(names, count)
