"""`rostool node`: list, info, ping, kill (rosnode's forms under ROS 1, ros2 node's under ROS 2)."""

from __future__ import annotations

import functools
import time
from typing import Any

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.graph.base import NodeInfo


@click.group()
def node() -> None:
    """Inspect and stop nodes (like rosnode, or ros2 node).

    Flags and output follow the selected ROS version (--ros1/--ros2, ROS_VERSION, detection): rosnode's
    forms under ROS 1, ros2 node's under ROS 2; --json works in both. ros2cli flags with no meaning here
    (--spin-time, -s/--use-sim-time) are accepted and ignored.

    \b
    Examples:
      rostool node list
      rostool node info /hello_world_pub_node
      rostool node ping /hello_world_pub_node -c 3
      rostool node kill /hello_world_pub_node
    """


def _ignored(func: Any) -> Any:
    """ros2cli's node options with no meaning here: accepted, said so in --help, ignored."""
    options = (
        click.option("--no-daemon", is_flag=True,
                     help="Ask the ROS 2 graph directly, not its daemon (ROSTOOL_NO_DAEMON=1)."),
        click.option("--spin-time", type=float, metavar="S",
                     help="Accepted and ignored (rostool waits for discovery to settle itself)."),
        click.option("-s", "--use-sim-time", is_flag=True, help="Accepted and ignored (wall clock)."),
    )  # fmt: skip

    @functools.wraps(func)
    def wrapper(
        *args: Any, no_daemon: bool, spin_time: float | None, use_sim_time: bool, **kwargs: Any
    ) -> Any:
        return func(*args, **kwargs)

    for option in reversed(options):
        wrapper = option(wrapper)
    return wrapper


@node.command("list")
@click.option(
    "-a",
    "--all",
    "show_all",
    is_flag=True,
    help="ROS 1: each node with its XML-RPC URI. ROS 2: hidden nodes (a name part starting with _) too.",
)
@click.option("-c", "--count-nodes", is_flag=True, help="Only the number of nodes.")
@json_option
@_ignored
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


@node.command("info")
@click.argument("name")
@click.option("--include-hidden", is_flag=True, help="ROS 2: hidden nodes, topics and services too.")
@json_option
@_ignored
@click.pass_context
def info(ctx: click.Context, name: str, include_hidden: bool, as_json: bool) -> None:
    """Show a node's publications, subscriptions, services and connections.

    \b
    Example:
      rostool node info /hello_world_pub_node
    """
    from rostool.errors import RostoolError
    from rostool.interfaces.names import hidden_name

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
            _info_ros2(details, as_json, include_hidden)
            return
        details = graph.node_info(name)
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


_SEND_GOAL = "/_action/send_goal"


def _actions(services: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """Actions told by their send_goal service: (/fibonacci, pkg/action/Fibonacci)."""
    return sorted(
        (n.removesuffix(_SEND_GOAL), t.removesuffix("_SendGoal"))
        for n, t in services
        if n.endswith(_SEND_GOAL)
    )


def _info_ros2(details: NodeInfo, as_json: bool, include_hidden: bool = False) -> None:
    """ros2 node info's form: the node's endpoints grouped by kind, with their types; actions are told by
    their hidden services, which (as every hidden name) show only with --include-hidden."""
    from rostool.interfaces.names import hidden_name

    def shown(entries: list[tuple[str, str]]) -> list[tuple[str, str]]:
        return sorted(e for e in entries if include_hidden or not hidden_name(e[0]))

    servers = [(s, details.service_types.get(s, "?")) for s in details.services]
    groups: tuple[tuple[str, list[tuple[str, str]]], ...] = (
        ("Subscribers", shown(details.subscriptions)), ("Publishers", shown(details.publications)),
        ("Service Servers", shown(servers)), ("Service Clients", shown(details.service_clients)),
        ("Action Servers", _actions(servers)), ("Action Clients", _actions(details.service_clients)),
    )  # fmt: skip
    if as_json:
        print_json({"name": details.name, **{title.lower().replace(" ", "_"): [
            {"name": n, "type": t} for n, t in entries] for title, entries in groups}})  # fmt: skip
        return
    lines = [details.name]
    for title, entries in groups:
        lines.append(f"  {title}:")
        # ros2 prints an empty section as its title and an empty line
        lines += [f"    {n}: {t}" for n, t in entries] or [""]
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
