"""`rostool node`: list, info, ping, kill (rosnode's forms)."""

from __future__ import annotations

import time

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.graph.base import NodeInfo


@click.group()
def node() -> None:
    """Inspect and stop nodes (like rosnode).

    \b
    Examples:
      rostool node list
      rostool node info /hello_world_pub_node
      rostool node ping /hello_world_pub_node -c 3
      rostool node kill /hello_world_pub_node
    """


@node.command("list")
@json_option
@click.pass_context
def list_nodes(ctx: click.Context, as_json: bool) -> None:
    """List the nodes registered with the master.

    \b
    Example:
      rostool node list
    """
    with live_graph(ctx) as graph:
        names = graph.node_names()
    if as_json:
        print_json(names)
        return
    for name in names:
        click.echo(name)


@node.command("info")
@click.argument("name")
@json_option
@click.pass_context
def info(ctx: click.Context, name: str, as_json: bool) -> None:
    """Show a node's publications, subscriptions, services and connections.

    \b
    Example:
      rostool node info /hello_world_pub_node
    """
    with live_graph(ctx) as graph:
        details = graph.node_info(name)
        if graph.style == "ros2":
            _info_ros2(details, as_json)
            return
        uris = {n: graph.node_uri(n) for n in graph.node_names()}
    if as_json:
        print_json(
            {
                "name": details.name,
                "uri": details.uri,
                "pid": details.pid,
                "publications": [{"topic": t, "type": ty} for t, ty in details.publications],
                "subscriptions": [{"topic": t, "type": ty} for t, ty in details.subscriptions],
                "services": details.services,
                "connections": [vars(c) for c in details.connections],
            }
        )
        return
    by_uri = {uri: n for n, uri in uris.items()}
    lines = ["-" * 80, f"Node [{details.name}]"]
    for title, entries in (("Publications", details.publications), ("Subscriptions", details.subscriptions)):
        if entries:
            lines += [f"{title}: ", *(f" * {t} [{ty}]" for t, ty in entries), ""]
        else:
            lines += [f"{title}: None", ""]
    if details.services:
        lines += ["Services: ", *(f" * {s}" for s in details.services), ""]
    else:
        lines += ["Services: None", ""]
    lines += ["", f"contacting node {details.uri} ...", f"Pid: {details.pid}"]
    if details.connections:
        lines.append("Connections:")
        for c in details.connections:
            peer = f"{by_uri[c.peer]} ({c.peer})" if c.peer in by_uri else c.peer
            lines += [
                f" * topic: {c.topic}",
                f"    * to: {peer}",
                f"    * direction: {c.direction}",
                f"    * transport: {c.transport}",
            ]
    click.echo("\n".join(lines) + "\n")


def _info_ros2(details: NodeInfo, as_json: bool) -> None:
    """ros2 node info's form: the node's endpoints grouped by kind, with their types."""
    servers = [(s, details.service_types.get(s, "?")) for s in details.services]
    groups: tuple[tuple[str, list[tuple[str, str]]], ...] = (
        ("Subscribers", details.subscriptions), ("Publishers", details.publications),
        ("Service Servers", servers), ("Service Clients", details.service_clients),
        ("Action Servers", []), ("Action Clients", []),
    )  # fmt: skip
    if as_json:
        print_json({"name": details.name, **{title.lower().replace(" ", "_"): [
            {"name": n, "type": t} for n, t in entries] for title, entries in groups}})  # fmt: skip
        return
    lines = [details.name]
    for title, entries in groups:
        lines.append(f"  {title}:")
        lines += [f"    {n}: {t}" for n, t in entries]
    click.echo("\n".join(lines))


@node.command("ping")
@click.argument("name")
@click.option("-c", "--count", type=click.IntRange(min=1), help="Ping N times (default: until Ctrl+C).")
@click.pass_context
def ping(ctx: click.Context, name: str, count: int | None) -> None:
    """Check that a node answers, and how fast.

    \b
    Example:
      rostool node ping /hello_world_pub_node -c 3
    """
    with live_graph(ctx) as graph:
        uri = graph.node_uri(name)
        click.echo(f"rosnode: node is [{name}]")
        click.echo(f"pinging {name} with a timeout of 3.0s")
        done = 0
        while count is None or done < count:
            if done:
                time.sleep(1.0)
            millis = graph.ping(name)
            click.echo(f"xmlrpc reply from {uri}\ttime={millis:f}ms")
            done += 1


@node.command("kill")
@click.argument("names", nargs=-1, required=True, metavar="NODE...")
@click.pass_context
def kill(ctx: click.Context, names: tuple[str, ...]) -> None:
    """Ask nodes to shut down.

    \b
    Example:
      rostool node kill /hello_world_pub_node
    """
    with live_graph(ctx) as graph:
        uris = {n: graph.node_uri(n) for n in names}  # every name checked before any is killed
        click.echo(
            "killing " + names[0] if len(names) == 1 else "killing:\n" + "\n".join(f" * {n}" for n in names)
        )
        for name in uris:
            graph.kill(name)
    click.echo("killed")
