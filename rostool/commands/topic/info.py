"""`rostool topic info`: rostopic info's form (type, publishers and subscribers with URIs), ros2 topic info's
(type and counts, with -v every endpoint)."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.errors import RostoolError
from rostool.graph.base import Graph


@click.command("info")
@click.argument("name")
@click.option("-v", "--verbose", is_flag=True, help="ROS 2: every endpoint with its node, GID and QoS.")
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def info(ctx: click.Context, name: str, verbose: bool, as_json: bool) -> None:
    """Show a topic's type, publishers and subscribers.

    \b
    Example:
      rostool topic info /hello_world
    """
    from rostool.output.endpoint_text import topic_info_text

    with live_graph(ctx) as graph:
        resolved = graph.resolve(name)
        found = next((t for t in graph.topics() if t.name == resolved), None)
        if found is None and graph.style == "ros2":
            raise RostoolError(f"Unknown topic '{resolved}'")
        if found is None:
            raise RostoolError(f"unknown topic {resolved}: no node publishes or subscribes to it")
        if graph.style == "ros2":
            endpoints = graph.topic_endpoints(found.name)
            if as_json:
                print_json({**vars(found), "endpoints": endpoints})
            else:
                click.echo(topic_info_text(found.type, endpoints, verbose), nl=False)
            return
        if verbose:
            raise RostoolError("topic info -v applies to ROS 2 graphs only")
        uris = {node: _node_uri(graph, node) for node in {*found.publishers, *found.subscribers}}
    if as_json:
        print_json({**vars(found), "uris": uris})
        return
    click.echo(f"Type: {found.type}\n")
    for title, nodes in (("Publishers", found.publishers), ("Subscribers", found.subscribers)):
        if nodes:
            click.echo(f"{title}: ")
            for node in nodes:
                click.echo(f" * {node} ({uris[node]})")
        else:
            click.echo(f"{title}: None")
        click.echo("")
    click.echo("")


def _node_uri(graph: Graph, node: str) -> str:
    try:
        return str(graph.node_uri(node))
    except RostoolError:
        return "unknown"
