"""`rostool node info`: rosnode info's publications, subscriptions, services and connections; ros2 node
info's endpoints by kind."""

from __future__ import annotations

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.node._options import ignored_node_options


@click.command("info")
@click.argument("name")
@click.option("--include-hidden", is_flag=True, help="ROS 2: hidden nodes, topics and services too.")
@json_option
@ignored_node_options
@click.pass_context
def info(ctx: click.Context, name: str, include_hidden: bool, as_json: bool) -> None:
    """Show a node's publications, subscriptions, services and connections.

    \b
    Example:
      rostool node info /hello_world_pub_node
    """
    from rostool.errors import RostoolError
    from rostool.interfaces.names import hidden_name
    from rostool.output.node_text import node_info_json, node_info_text, ros2_node_groups, ros2_node_text

    with live_graph(ctx) as graph:
        if graph.style == "ros2":
            resolved = graph.resolve(name)
            if hidden_name(resolved) and not include_hidden:
                raise RostoolError(f"Unable to find node '{resolved}'")
            try:
                details = graph.node_info(name)
            except RostoolError as err:
                raise RostoolError(f"Unable to find node '{resolved}'") from err
            twins = graph.node_names().count(resolved)
            if twins > 1:  # ros2 node info's warning
                click.echo(
                    f'There are {twins} nodes in the graph with the exact name "{resolved}". '
                    "You are seeing information about only one of them.",
                    err=True,
                )
            groups = ros2_node_groups(details, include_hidden)
            if as_json:
                print_json({"name": details.name, **{title.lower().replace(" ", "_"): [
                    {"name": n, "type": t} for n, t in entries] for title, entries in groups}})  # fmt: skip
            else:
                click.echo(ros2_node_text(details.name, groups))
            return
        details = graph.node_info(name)
        uris = {n: graph.node_uri(n) for n in graph.node_names()}
    if as_json:
        print_json(node_info_json(details))
    else:
        click.echo(node_info_text(details, uris))
