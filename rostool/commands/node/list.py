"""`rostool node list`: rosnode list's forms (-a with URIs), ros2 node list's (-a hidden nodes, -c)."""

from __future__ import annotations

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.node._options import ignored_node_options


@click.command("list")
@click.option("-a", "--all", "show_all", is_flag=True, help="ROS 1: each node with its XML-RPC URI. ROS 2: "
              "hidden nodes (a name part starting with _) too.")  # fmt: skip
@click.option("-c", "--count-nodes", is_flag=True, help="Only the number of nodes.")
@json_option
@ignored_node_options
@click.pass_context
def list_nodes(ctx: click.Context, show_all: bool, count_nodes: bool, as_json: bool) -> None:
    """List the nodes of the live graph.

    \b
    Examples:
      rostool node list
      rostool --ros2 node list -a -c
    """
    from rostool.interfaces.names import hidden_name

    with live_graph(ctx) as graph:
        names = graph.node_names()
        ros2 = graph.style == "ros2"
        if ros2 and not show_all:
            names = [n for n in names if not hidden_name(n)]
        uris = {n: graph.node_uri(n) for n in names} if show_all and not ros2 and not count_nodes else {}
    if count_nodes:
        click.echo(str(len(names)))
        return
    if as_json:
        print_json(names)
        return
    if ros2 and len(set(names)) < len(names):
        click.echo(
            "WARNING: Be aware that there are nodes in the graph that share an exact name, which can have "
            "unintended side effects.",
            err=True,
        )
    for name in names:
        click.echo(f"{uris[name]} \t{name}" if name in uris else name)
