"""`rostool service`: list, type, info, uri, node, args, find, call (rosservice's forms and output; on ROS 2
list, type, info, find and call in ros2 service's forms and output)."""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

import click

from rostool.commands._common import json_option, live_graph, print_json, ros_version
from rostool.commands.srv import interfaces_option
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.graph.ros1.graph import Ros1Graph
    from rostool.graph.ros2.graph import Ros2Graph

_SRV_TYPE = re.compile(r"[A-Za-z]\w*/(srv/)?[A-Za-z]\w*\Z")
ROS2_WAIT_SECONDS = 5.0  # how long `call` gives a seen (or given) service's server to match without --wait


@click.group()
def service() -> None:
    """Inspect and call services (like rosservice; on ROS 2 like ros2 service). Types come from the service
    itself and from .srv files in source trees (--interfaces, ROS_PACKAGE_PATH, the current workspace; on
    ROS 2 also AMENT_PREFIX_PATH): no build needed.

    \b
    Examples:
      rostool service list
      rostool service type /sum_two_ints
      rostool service call /sum_two_ints 7 8
      rostool service call /sum_two_ints "{a: 7, b: 8}" --json
      rostool --ros2 service call /add_two_ints example_interfaces/srv/AddTwoInts "{a: 1, b: 2}"
      rostool --ros2 service info /add_two_ints
    """


def is_ros2(ctx: click.Context) -> bool:
    """Whether ROS 2 is selected (decided before any graph starts)."""
    from rostool.graph import select_ros_version

    return select_ros_version(ros_version(ctx)) == 2


@contextmanager
def ros2_graph(ctx: click.Context, interface_paths: tuple[str, ...] = ()) -> Iterator[Ros2Graph]:
    from rostool.graph.ros2.graph import Ros2Graph

    with live_graph(ctx, interface_paths) as graph:
        if not isinstance(graph, Ros2Graph):
            raise RostoolError("this form needs a ROS 2 graph (--ros2 or ROS_VERSION=2)")
        yield graph


def _hidden(name: str) -> bool:
    """ros2cli hides names with a token starting with `_` (e.g. actions' `/x/_action/send_goal`)."""
    return any(token.startswith("_") for token in name.split("/"))


def srv_store_name(type_name: str) -> str:
    """`pkg/Name` or `pkg/srv/Name` -> `pkg/srv/Name`."""
    pkg, _, name = type_name.strip().strip("/").rpartition("/")
    return f"{pkg.removesuffix('/srv')}/srv/{name}"


@contextmanager
def ros1_graph(ctx: click.Context, what: str = "services") -> Iterator[Ros1Graph]:
    """The live ROS 1 graph; a clear error (before any DDS start-up) when ROS 2 is selected."""
    from rostool.graph import select_ros_version
    from rostool.graph.ros1.graph import Ros1Graph

    if select_ros_version(ros_version(ctx)) != 1:
        raise RostoolError(
            f"{what}: supported on ROS 1 graphs only in this rostool version; "
            "use --ros1 (or set ROS_MASTER_URI) with a ROS 1 master"
        )
    with live_graph(ctx) as graph:
        if not isinstance(graph, Ros1Graph):
            raise RostoolError(f"{what}: supported on ROS 1 graphs only in this rostool version")
        yield graph


@service.command("list")
@click.argument("namespace", required=False)
@click.option("-n", "--nodes", "with_nodes", is_flag=True, help="Also print the node providing each service.")
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: also print each service's type.")
@click.option(
    "-a", "--include-hidden-services", "hidden", is_flag=True, help="ROS 2: also list hidden services."
)
@json_option
@click.pass_context
def list_services(
    ctx: click.Context, namespace: str | None, with_nodes: bool, show_types: bool, hidden: bool, as_json: bool
) -> None:
    """List the services of the live graph (optionally only those under NAMESPACE).

    \b
    Examples:
      rostool service list
      rostool service list -n /sum_server
      rostool --ros2 service list -t          # /add_two_ints [example_interfaces/srv/AddTwoInts]
    """
    from rostool.graph.ros1.names import resolve
    from rostool.graph.ros1.services import services

    if is_ros2(ctx):
        _list_ros2(ctx, namespace, with_nodes, show_types, hidden, as_json)
        return
    if show_types or hidden:
        raise RostoolError("service list -t / -a apply to ROS 2 graphs only (ROS 1: `rostool service type`)")
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


def _list_ros2(
    ctx: click.Context, namespace: str | None, with_nodes: bool, show_types: bool, hidden: bool, as_json: bool
) -> None:
    with ros2_graph(ctx) as graph:
        found = [s for s in graph.services() if hidden or not _hidden(s[0])]
        if namespace:
            prefix = graph.resolve(namespace).rstrip("/") + "/"
            found = [s for s in found if s[0] == prefix[:-1] or s[0].startswith(prefix)]
    if as_json:
        print_json([{"name": name, "type": type_, "nodes": nodes} for name, type_, nodes in found])
        return
    for name, type_, nodes in found:
        line = f"{name} [{type_}]" if show_types else name
        click.echo(f"{line} {','.join(nodes)}" if with_nodes else line)


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

    if is_ros2(ctx):
        with ros2_graph(ctx) as graph2:
            found = graph2.find_service_type(name)
            if found is None:
                raise RostoolError(f"unknown service {graph2.resolve(name)}: no server announces it")
        click.echo(found)
        return
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

    with ros1_graph(ctx, "service uri") as graph:
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
    with ros1_graph(ctx, "service node (on ROS 2: service list -n)") as graph:
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

    with ros1_graph(ctx, "service args") as graph:
        master = graph.master
        found = service_type(master, interfaces(interface_paths), name, lookup(master, name))
    click.echo(found.request_args())


@service.command("info")
@click.argument("name", metavar="SERVICE")
@click.option("-v", "--verbose", is_flag=True, help="ROS 2: each client and server with node, GIDs, QoS.")
@interfaces_option
@json_option
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
    from rostool.graph.ros1.services import service_info
    from rostool.interfaces.sources import InterfaceError, interfaces
    from rostool.interfaces.srv import load_service

    if is_ros2(ctx):
        _info_ros2(ctx, name, verbose, as_json)
        return
    if verbose:
        raise RostoolError("service info -v applies to ROS 2 graphs only")
    with ros1_graph(ctx, "service info") as graph:
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


def _info_ros2(ctx: click.Context, name: str, verbose: bool, as_json: bool) -> None:
    """ros2 service info: the type, then the clients and servers (counted, or listed with -v)."""
    with ros2_graph(ctx) as graph:
        found = graph.service_info(name)
        if found is None:
            raise RostoolError(
                f"unknown service {graph.resolve(name)}: no client or server announces it "
                "(see `rostool service list -a`)"
            )
    if as_json:
        print_json(found)
        return
    types = found["types"]
    lines = [f"Type: {types[0] if len(types) == 1 else types}"]
    for title, rows in (("Clients", found["clients"]), ("Services", found["servers"])):
        lines.append(f"{title} count: {len(rows)}")
        for row in rows if verbose else []:
            lines += ["", *_endpoint_lines(row)]
        if verbose:
            lines.append("")
    click.echo("\n".join(lines))


_ENDPOINT_TITLES = {
    ("CLIENT", "request"): "Request Writer", ("CLIENT", "reply"): "Response Reader",
    ("SERVER", "request"): "Request Reader", ("SERVER", "reply"): "Response Writer",
}  # fmt: skip


def _endpoint_lines(row: dict[str, Any]) -> list[str]:
    """One client or server the way rclpy's ServiceEndpointInfo prints it."""
    namespace, _, node = row["node"].rpartition("/")
    endpoints = row["endpoints"]
    lines = [
        f"Node name: {node}", f"Node namespace: {namespace or '/'}", f"Service type: {row['type']}",
        f"Service type hash: {row['type_hash'] or 'UNKNOWN'}", f"Endpoint type: {row['endpoint_type']}",
        f"Endpoint count: {len(endpoints)}",
    ]  # fmt: skip
    role = row["endpoint_type"]
    kinds = [kind for kind in ("request", "reply") if kind in endpoints]
    titled = [(_ENDPOINT_TITLES[(role, kind)], endpoints[kind]) for kind in kinds]
    if len(titled) == 1:
        lines += [f"GID: {titled[0][1]['gid']}", "QoS profile:", *_qos_lines(titled[0][1]["qos"], "  ")]
        return lines
    lines += ["GIDs:", *(f" - {title} : {e['gid']}" for title, e in titled), "QoS profiles:"]
    for title, endpoint in titled:
        lines += [f" - {title} :", *_qos_lines(endpoint["qos"], "      ")]
    return lines


def _qos_lines(qos: dict[str, Any], indent: str) -> list[str]:
    depth = f"KEEP_LAST ({qos['depth']})" if qos["depth"] else "KEEP_ALL"
    return [
        f"{indent}Reliability: {str(qos['reliability']).upper()}",
        f"{indent}History (Depth): {depth}",
        f"{indent}Durability: {str(qos['durability']).upper()}",
    ]


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

    if is_ros2(ctx):
        wanted = srv_store_name(type_name)
        with ros2_graph(ctx) as graph2:
            for name, type_, _nodes in graph2.services():
                if type_ == wanted and not _hidden(name):
                    click.echo(name)
        return
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
    and its .srv found in the sources (see --interfaces). On ROS 2, ros2 service call's form: an optional
    TYPE (pkg/srv/Name or pkg/Name; default: the type the server announces) before the values.

    \b
    Examples:
      rostool service call /sum_two_ints 7 8
      rostool service call /sum_two_ints "{a: 7, b: 8}"
      rostool service call /set_enabled true --wait --timeout 5
      rostool service call /reset
      rostool --ros2 service call /add_two_ints example_interfaces/srv/AddTwoInts "{a: 1, b: 2}"
      rostool --ros2 service call /add_two_ints "{a: 1, b: 2}" --json
      rostool --ros2 service call /rate robo_msgs/srv/Rate "{factor: 2}" --interfaces ~/ros2_ws
    """
    from rostool.graph.ros1 import services
    from rostool.interfaces.sources import interfaces
    from rostool.output.plain import to_plain
    from rostool.output.yaml_text import to_yaml

    if is_ros2(ctx):
        with ros2_graph(ctx, interface_paths) as graph2:
            request, response = _call_ros2(graph2, name, values, wait, timeout)
            if as_json:
                print_json(to_plain(response, "ros2"))
            else:
                click.echo(f"requester: making request: {message_repr(request)}\n")
                click.echo(f"response:\n{message_repr(response)}\n")
        return
    with ros1_graph(ctx) as graph:
        _srv, response = services.call(
            graph.master, interfaces(interface_paths), name, values, wait=wait, timeout=timeout
        )
    if as_json:
        print_json(to_plain(response))
    else:
        click.echo(to_yaml(response))


def _call_ros2(
    graph: Ros2Graph, name: str, values: tuple[str, ...], wait: bool, timeout: float | None
) -> tuple[Any, Any]:
    """Find the type (given or announced), build the request, wait for the server, call."""
    import time

    resolved = graph.resolve(name)
    srv_type = values[0] if values and _SRV_TYPE.match(values[0]) else None
    if srv_type is not None:
        values = values[1:]
    limit = timeout if timeout is not None else (math.inf if wait else ROS2_WAIT_SECONDS)
    deadline = time.monotonic() + limit
    while srv_type is None:
        srv_type = graph.find_service_type(resolved)
        if srv_type is None and (not wait or time.monotonic() >= deadline):
            raise RostoolError(
                f"unknown service {resolved}: no server announces it (see `rostool service list`); "
                "give its TYPE after the name to wait for it with --wait"
            )
        if srv_type is None:
            time.sleep(0.1)
    client = graph.service_client(resolved, srv_type)
    request = graph.build_message(client.request_type, _request_value(graph, client.request_type, values))
    remaining = max(deadline - time.monotonic(), 0.001)
    if not client.wait_for_server(remaining):
        hint = "" if wait else " (--wait waits for it)"
        raise RostoolError(f"service {resolved} is not available: no server matched within {limit:g} s{hint}")
    return request, client.call(request, timeout if timeout is not None else math.inf)


def _request_value(graph: Ros2Graph, request_type: str, values: tuple[str, ...]) -> Any:
    """One YAML mapping, or the request fields in order (as `rosservice call` takes them)."""
    from rostool.graph.ros1.services import parse_args
    from rostool.output.plain import field_names

    parsed = parse_args(values)
    if not parsed:
        return {}
    if len(parsed) == 1 and isinstance(parsed[0], dict):
        return parsed[0]
    fields = field_names(graph.message_class(request_type))
    if len(parsed) != len(fields):
        srv = request_type.removesuffix("_Request")
        raise RostoolError(
            f"{srv} takes {len(fields)} request value(s) in this order: {' '.join(fields) or '(none)'}; "
            f"got {len(parsed)}. Give them in order or as one YAML mapping"
        )
    return dict(zip(fields, parsed, strict=True))


def message_repr(value: Any) -> str:
    """A message as rclpy's repr shows it: `pkg.srv.Name_Request(a=1, b=2)`."""
    from rostool.output.plain import is_message, message_fields

    if is_message(value):
        fields = ", ".join(f"{k}={message_repr(v)}" for k, v in message_fields(value))
        return f"{getattr(value, '__msgtype__', type(value).__name__).replace('/', '.')}({fields})"
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(message_repr(v) for v in value) + "]"
    return repr(value)
