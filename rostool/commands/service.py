"""`rostool service`: list, type, info, uri, node, args, find, call (rosservice's forms and output)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

import click

from rostool.commands._common import json_option, live_graph, print_json, ros_version
from rostool.commands.srv import interfaces_option
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.graph.ros1.graph import Ros1Graph


@click.group()
def service() -> None:
    """Inspect and call services (like rosservice). Types come from the service itself and from
    .srv files in source trees (--interfaces, ROS_PACKAGE_PATH, the current workspace): no build needed.

    \b
    Examples:
      rostool service list
      rostool service type /sum_two_ints
      rostool service call /sum_two_ints 7 8
      rostool service call /sum_two_ints "{a: 7, b: 8}" --json
    """


@contextmanager
def ros1_graph(ctx: click.Context, what: str = "services") -> Iterator[Ros1Graph]:
    """The live ROS 1 graph; a clear error (before any DDS start-up) when ROS 2 is selected."""
    from rostool.graph import select_ros_version
    from rostool.graph.ros1.graph import Ros1Graph

    if select_ros_version(ros_version(ctx)) != 1:
        raise RostoolError(
            f"{what} are supported on ROS 1 graphs only in this rostool version; "
            "use --ros1 (or set ROS_MASTER_URI) with a ROS 1 master"
        )
    with live_graph(ctx) as graph:
        if not isinstance(graph, Ros1Graph):
            raise RostoolError(f"{what} are supported on ROS 1 graphs only in this rostool version")
        yield graph


@service.command("list")
@click.argument("namespace", required=False)
@click.option("-n", "--nodes", "with_nodes", is_flag=True, help="Also print the node providing each service.")
@json_option
@click.pass_context
def list_services(ctx: click.Context, namespace: str | None, with_nodes: bool, as_json: bool) -> None:
    """List the services of the live graph (optionally only those under NAMESPACE).

    \b
    Examples:
      rostool service list
      rostool service list -n /sum_server
    """
    from rostool.graph.ros1.names import resolve
    from rostool.graph.ros1.services import services

    with ros1_graph(ctx) as graph:
        found = services(graph.master)
    if namespace:
        prefix = resolve(namespace).rstrip("/") + "/"
        found = [(s, n) for s, n in found if s == prefix[:-1] or s.startswith(prefix)]
    if as_json:
        print_json([{"name": s, "nodes": n} for s, n in found])
    elif with_nodes:
        for name, nodes in found:
            click.echo(f"{name} {','.join(nodes)}")
    else:
        for name, _nodes in found:
            click.echo(name)


@service.command("type")
@click.argument("name", metavar="SERVICE")
@click.pass_context
def type_(ctx: click.Context, name: str) -> None:
    """Print the type of a service (asked from the service itself).

    \b
    Example:
      rostool service type /sum_two_ints      # sum_two_numbers/SumTwoInts
    """
    from rostool.graph.ros1.services import service_info

    with ros1_graph(ctx) as graph:
        click.echo(service_info(graph.master, name).type)


@service.command("uri")
@click.argument("name", metavar="SERVICE")
@click.pass_context
def uri(ctx: click.Context, name: str) -> None:
    """Print the rosrpc:// address of a service.

    \b
    Example:
      rostool service uri /sum_two_ints
    """
    from rostool.graph.ros1.services import lookup

    with ros1_graph(ctx) as graph:
        click.echo(lookup(graph.master, name))


@service.command("node")
@click.argument("name", metavar="SERVICE")
@click.pass_context
def node(ctx: click.Context, name: str) -> None:
    """Print the node that provides a service.

    \b
    Example:
      rostool service node /sum_two_ints
    """
    from rostool.graph.ros1.names import resolve
    from rostool.graph.ros1.services import services

    resolved = resolve(name)
    with ros1_graph(ctx) as graph:
        nodes = next((n for s, n in services(graph.master) if s == resolved), None)
    if not nodes:
        raise RostoolError(f"unknown service {resolved}: no node provides it (see `rostool service list`)")
    click.echo("\n".join(nodes))


@service.command("args")
@click.argument("name", metavar="SERVICE")
@interfaces_option
@click.pass_context
def args(ctx: click.Context, name: str, interface_paths: tuple[str, ...]) -> None:
    """Print the request field names of a service, in the order `call` takes them.

    \b
    Example:
      rostool service args /sum_two_ints      # a b
    """
    from rostool.graph.ros1.services import lookup, service_type
    from rostool.interfaces.sources import interfaces

    with ros1_graph(ctx) as graph:
        master = graph.master
        found = service_type(master, interfaces(interface_paths), name, lookup(master, name))
    click.echo(found.request_args())


@service.command("info")
@click.argument("name", metavar="SERVICE")
@interfaces_option
@json_option
@click.pass_context
def info(ctx: click.Context, name: str, interface_paths: tuple[str, ...], as_json: bool) -> None:
    """Print a service's node, URI, type and request arguments.

    \b
    Example:
      rostool service info /sum_two_ints
    """
    from rostool.graph.ros1.services import service_info
    from rostool.interfaces.sources import InterfaceError, interfaces
    from rostool.interfaces.srv import load_service

    with ros1_graph(ctx) as graph:
        found = service_info(graph.master, name)
    try:
        request_args: str | None = load_service(interfaces(interface_paths), found.type).request_args()
    except InterfaceError:
        request_args = None
    if as_json:
        print_json({"name": found.name, "node": found.node, "uri": found.uri, "type": found.type,
                    "md5sum": found.md5sum,
                    "args": request_args.split() if request_args is not None else None})  # fmt: skip
        return
    click.echo(f"Node: {found.node}\nURI: {found.uri}\nType: {found.type}")
    if request_args is None:
        click.echo(f"Args: ? (no {found.type}.srv found; see --interfaces)")
    else:
        click.echo(f"Args: {request_args}")


@service.command("find")
@click.argument("type_name", metavar="TYPE")
@click.pass_context
def find(ctx: click.Context, type_name: str) -> None:
    """List the services of type TYPE.

    \b
    Example:
      rostool service find std_srvs/Trigger
    """
    from rostool.graph.ros1.services import lookup, probe, services

    with ros1_graph(ctx) as graph:
        master = graph.master
        for name, _nodes in services(master):
            try:
                found = probe(name, lookup(master, name), master.caller_id).get("type")
            except RostoolError:
                continue  # a service that vanished or does not answer is not a match
            if found == type_name:
                click.echo(name)


@service.command("call", context_settings={"ignore_unknown_options": True})  # negative numbers are values
@click.argument("name", metavar="SERVICE")
@click.argument("values", nargs=-1)
@click.option("--wait", is_flag=True, help="Wait for the service to be advertised first.")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    help="Give up after S seconds (waiting, connecting and the call itself).",
)
@interfaces_option
@json_option
@click.pass_context
def call(
    ctx: click.Context,
    name: str,
    values: tuple[str, ...],
    wait: bool,
    timeout: float | None,
    interface_paths: tuple[str, ...],
    as_json: bool,
) -> None:
    """Call a service and print its response (YAML like rosservice, or --json).

    VALUES are the request fields in order, or one YAML mapping. The type is asked from the service
    and its .srv found in the sources (see --interfaces).

    \b
    Examples:
      rostool service call /sum_two_ints 7 8
      rostool service call /sum_two_ints "{a: 7, b: 8}"
      rostool service call /set_enabled true --wait --timeout 5
      rostool service call /reset
    """
    from rostool.graph.ros1 import services
    from rostool.interfaces.sources import interfaces
    from rostool.output.plain import to_plain
    from rostool.output.yaml_text import to_yaml

    with ros1_graph(ctx) as graph:
        _srv, response = services.call(
            graph.master, interfaces(interface_paths), name, values, wait=wait, timeout=timeout
        )
    if as_json:
        print_json(to_plain(response))
    else:
        click.echo(to_yaml(response))
