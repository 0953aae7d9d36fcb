"""`rostool service list`: rosservice list's forms (-n, NAMESPACE), ros2 service list's (-t, -a, -c)."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.commands.service._options import count_option, hidden_services_option
from rostool.errors import RostoolError


@click.command("list")
@click.argument("namespace", required=False)
@click.option("-n", "--nodes", "with_nodes", is_flag=True, help="Also print the node providing each service.")
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: also print each service's type.")
@hidden_services_option
@count_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def list_services(
    ctx: click.Context, namespace: str | None, with_nodes: bool, show_types: bool, hidden: bool, count: bool,
    as_json: bool,
) -> None:  # fmt: skip
    """List the services of the live graph (optionally only those under NAMESPACE).

    \b
    Examples:
      rostool service list
      rostool service list -n /sum_server
      rostool --ros2 service list -t          # /add_two_ints [example_interfaces/srv/AddTwoInts]
    """
    from rostool.interfaces.names import hidden_name

    with live_graph(ctx) as graph:
        if graph.style == "ros1" and (show_types or hidden):
            raise RostoolError(
                "service list -t / -a apply to ROS 2 graphs only (ROS 1: `rostool service type`)"
            )
        found = [s for s in graph.services() if hidden or graph.style == "ros1" or not hidden_name(s[0])]
        if namespace:
            prefix = graph.resolve(namespace).rstrip("/") + "/"
            found = [s for s in found if s[0] == prefix[:-1] or s[0].startswith(prefix)]
    if count:
        click.echo(str(len(found)))
    elif as_json:
        print_json([{"name": n, **({} if t is None else {"type": t}), "nodes": ns} for n, t, ns in found])
    else:
        for name, type_, nodes in found:
            line = f"{name} [{type_}]" if show_types else name
            click.echo(f"{line} {','.join(nodes)}" if with_nodes else line)
