"""`rostool action info`: actionlib's type, server, clients and goals; ros2 action info's clients and
servers."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.commands.action._options import ros2_flags
from rostool.errors import RostoolError


@click.command("info")
@click.argument("name", metavar="ACTION")
@click.option("--wait", "wait", type=click.FloatRange(min=0), default=2.0, show_default=True,
              help="Seconds to wait for the server's goal status list.")  # fmt: skip
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: each client and server with the type.")
@click.option("-c", "--count", is_flag=True, help="ROS 2: only the numbers of clients and servers.")
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def info(ctx: click.Context, name: str, wait: float, show_types: bool, count: bool, as_json: bool) -> None:
    """Show an action's type, server, clients and the goals its server tracks (ROS 2: its clients and
    servers, as ros2 action info does; for an action nobody serves, 0 of each and then the error).

    \b
    Examples:
      rostool action info /navigate_2d_action
      rostool --ros2 action info -t /fibonacci
    """
    from rostool.output.goal_text import action_info_text

    with live_graph(ctx) as graph:
        ros2_flags(graph, "info", show_types=show_types, count=count)
        style = graph.style
        if style == "ros2" and graph.resolve(name) not in {a.name for a in graph.actions()}:
            found = {"name": graph.resolve(name), "type": None, "clients": [], "servers": []}
        else:
            found = graph.action_info(name, wait)
    if as_json:
        print_json(found)
    elif style == "ros1":
        click.echo(action_info_text(found, wait))
    else:
        click.echo(f"Action: {name}")
        for title, nodes in (("Action clients", found["clients"]), ("Action servers", found["servers"])):
            click.echo(f"{title}: {len(nodes)}")
            for node in [] if count else nodes:
                click.echo(f"    {node} [{found['type']}]" if show_types else f"    {node}")
        if not found["servers"] and not found["clients"]:  # ros2 exits 0 here; an unknown name is an error
            raise RostoolError(
                f"unknown action {found['name']}: no server announces it (`rostool action list`)"
            )
