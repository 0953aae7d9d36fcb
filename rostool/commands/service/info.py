"""`rostool service info`: rosservice info's node, URI, type and args; ros2 service info's type and counts."""

from __future__ import annotations

import click

from rostool.commands._common import (
    ignored_ros2_options,
    interfaces_option,
    json_option,
    live_graph,
    print_json,
)
from rostool.errors import RostoolError


@click.command("info")
@click.argument("name", metavar="SERVICE")
@click.option("-v", "--verbose", is_flag=True, help="ROS 2: each client and server with node, GIDs, QoS.")
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def info(
    ctx: click.Context, name: str, verbose: bool, interface_paths: tuple[str, ...], as_json: bool
) -> None:
    """Print a service's node, URI, type and request arguments (ROS 2: its type and how many clients and
    servers it has, as ros2 service info does).

    \b
    Examples:
      rostool service info /sum_two_ints
      rostool --ros2 service info /add_two_ints -v
    """
    from rostool.output.endpoint_text import service_info_text

    with live_graph(ctx, interface_paths) as graph:
        if verbose and graph.style == "ros1":
            raise RostoolError("service info -v applies to ROS 2 graphs only")
        found = graph.service_info(name)
        if found is None:
            raise RostoolError(
                f"unknown service {graph.resolve(name)}: no client or server announces it "
                "(see `rostool service list -a`)"
            )
        style = graph.style
    if as_json:
        print_json(found)
    elif style == "ros1":
        args = found["args"]
        args_text = f"? (no {found['type']}.srv found; see --interfaces)" if args is None else " ".join(args)
        click.echo(f"Node: {found['node']}\nURI: {found['uri']}\nType: {found['type']}\nArgs: {args_text}")
    else:
        click.echo(service_info_text(found, verbose))
