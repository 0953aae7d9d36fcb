"""`rostool service`: list, type, info, uri, node, args, find, call (rosservice's forms and output; on ROS 2
list, type, info, find and call in ros2 service's forms and output)."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.srv import interfaces_option
from rostool.errors import RostoolError
from rostool.graph.base import hidden_name


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
    with live_graph(ctx) as graph:
        if graph.style == "ros1" and (show_types or hidden):
            raise RostoolError(
                "service list -t / -a apply to ROS 2 graphs only (ROS 1: `rostool service type`)"
            )
        found = [s for s in graph.services() if hidden or graph.style == "ros1" or not hidden_name(s[0])]
        if namespace:
            prefix = graph.resolve(namespace).rstrip("/") + "/"
            found = [s for s in found if s[0] == prefix[:-1] or s[0].startswith(prefix)]
    if as_json:
        print_json([{"name": n, **({} if t is None else {"type": t}), "nodes": ns} for n, t, ns in found])
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
    with live_graph(ctx) as graph:
        click.echo(graph.service_type(name))


@service.command("uri")
@click.argument("name", metavar="SERVICE")
@click.pass_context
def uri(ctx: click.Context, name: str) -> None:
    """Print the rosrpc:// address of a service.

    \b
    Example:
      rostool service uri /sum_two_ints
    """
    with live_graph(ctx) as graph:
        click.echo(graph.service_uri(name))


@service.command("node")
@click.argument("name", metavar="SERVICE")
@click.pass_context
def node(ctx: click.Context, name: str) -> None:
    """Print the node that provides a service.

    \b
    Example:
      rostool service node /sum_two_ints
    """
    with live_graph(ctx) as graph:
        click.echo("\n".join(graph.service_nodes(name)))


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
    with live_graph(ctx, interface_paths) as graph:
        click.echo(graph.service_args(name))


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
        _info_ros2(found, verbose)


def _info_ros2(found: dict[str, Any], verbose: bool) -> None:
    """ros2 service info: the type, then the clients and servers (counted, or listed with -v)."""
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
    depth = {None: "UNKNOWN", 0: "KEEP_ALL"}.get(qos["depth"], f"KEEP_LAST ({qos['depth']})")
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
    with live_graph(ctx) as graph:
        for name in graph.find_services(type_name):
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
    from rostool.output.plain import to_plain
    from rostool.output.yaml_text import to_yaml

    with live_graph(ctx, interface_paths) as graph:
        request, response = graph.service_call(name, values, wait, timeout)
        style = graph.style
    if as_json:
        print_json(to_plain(response, style))
    elif style == "ros1":
        click.echo(to_yaml(response))
    else:
        click.echo(f"requester: making request: {message_repr(request)}\n")
        click.echo(f"response:\n{message_repr(response)}\n")


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
