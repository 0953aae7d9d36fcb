"""`rostool action list`: the actions of the live graph (ros2 action list's -t and -c)."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.commands.action._options import count_option, ros2_flags


@click.command("list")
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: also print each action's type.")
@count_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def list_actions(ctx: click.Context, show_types: bool, count: bool, as_json: bool) -> None:
    """List the actions of the live graph (namespaces with goal, cancel, status, feedback, result; on ROS 2
    actions with a server).

    \b
    Examples:
      rostool action list
      rostool --ros2 action list -t          # /fibonacci [example_interfaces/action/Fibonacci]
    """
    with live_graph(ctx) as graph:
        ros2_flags(graph, "list", show_types=show_types)
        found = graph.actions()
    if count:
        click.echo(str(len(found)))
    elif as_json:
        print_json([vars(a) for a in found])
    else:
        for summary in found:
            click.echo(f"{summary.name} [{summary.type}]" if show_types else summary.name)
