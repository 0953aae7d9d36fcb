"""`rostool service`: list, type, info, uri, node, args, find, call (rosservice's forms and output; on ROS 2
list, type, info, find and call in ros2 service's forms and output)."""

from __future__ import annotations

import sys
import time
from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.commands.srv import interfaces_option
from rostool.errors import RostoolError
from rostool.interfaces.names import hidden_name
from rostool.output.repr_text import message_repr


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
      rostool --ros2 service echo /add_two_ints      # needs the service's introspection on

    Flags and output follow the selected ROS version: rosservice's under ROS 1, ros2 service's under
    ROS 2. --json works in both. ros2cli flags with no meaning here (--spin-time,
    -s/--use-sim-time) are accepted and ignored.
    """


hidden_services_option = click.option(
    "-a", "--include-hidden-services", "--all", "hidden", is_flag=True,
    help="ROS 2: also hidden services (a name part starting with _).",
)  # fmt: skip
count_option = click.option(
    "-c", "--count-services", "--count", "count", is_flag=True, help="Only the number of services."
)


@service.command("list")
@click.argument("namespace", required=False)
@click.option("-n", "--nodes", "with_nodes", is_flag=True, help="Also print the node providing each service.")
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: also print each service's type.")
@hidden_services_option
@count_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def list_services(
    ctx: click.Context, namespace: str | None, with_nodes: bool, show_types: bool, hidden: bool, count: bool,
    as_json: bool,
) -> None:  # fmt: skip
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
    if count:
        click.echo(str(len(found)))
        return
    if as_json:
        print_json([{"name": n, **({} if t is None else {"type": t}), "nodes": ns} for n, t, ns in found])
        return
    for name, type_, nodes in found:
        line = f"{name} [{type_}]" if show_types else name
        click.echo(f"{line} {','.join(nodes)}" if with_nodes else line)


@service.command("type")
@click.argument("name", metavar="SERVICE")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def type_(ctx: click.Context, name: str) -> None:
    """Print the type of a service (asked from the service itself).

    \b
    Examples:
      rostool service type /sum_two_ints      # sum_two_numbers/SumTwoInts
      rostool --ros2 service type /add_two_ints   # example_interfaces/srv/AddTwoInts
    """
    with live_graph(ctx) as graph:
        if graph.style == "ros2":  # as ros2 service type: the announced type(s), or nothing and exit 1
            types = sorted({t for n, t, _ in graph.services() if n == graph.resolve(name) and t})
            if not types:  # as ros2 service type: nothing on stdout, exit 1
                resolved = graph.resolve(name)
                raise RostoolError(
                    f"unknown service {resolved}: no server announces it (`rostool service list`)"
                )
            click.echo("\n".join(types))
            return
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
@hidden_services_option
@count_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def find(ctx: click.Context, type_name: str, hidden: bool, count: bool) -> None:
    """List the services of type TYPE.

    \b
    Examples:
      rostool service find std_srvs/Trigger
      rostool --ros2 service find std_srvs/srv/SetBool -c
    """
    with live_graph(ctx) as graph:
        if graph.style == "ros1" and hidden:
            raise RostoolError("service find -a applies to ROS 2 graphs only")
        if graph.style == "ros2":
            from rostool.interfaces.names import to_store_name

            wanted = {type_name, to_store_name(type_name, "srv")}
            names = sorted(
                n for n, t, _ in graph.services() if t in wanted and (hidden or not hidden_name(n))
            )
        else:
            names = graph.find_services(type_name)
    click.echo(str(len(names)) if count else "\n".join(names), nl=count or bool(names))


@service.command("echo")
@click.argument("name", metavar="SERVICE")
@click.option("-n", "count", type=click.IntRange(min=1), help="Stop after N events.")
@click.option("--once", is_flag=True, help="Stop after one event.")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), help="Give up after S seconds idle.")
@click.option("--csv", "as_csv", is_flag=True, help="Each event as a CSV row.")
@click.option("--no-arr", "noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--no-str", "nostr", is_flag=True, help="Show strings as their length.")
@click.option("-l", "--truncate-length", type=click.IntRange(min=0), help="Cut strings and arrays after N.")
@click.option("-f", "--full-length", is_flag=True, help="Never truncate.")
@click.option("--flow-style", is_flag=True, help="YAML in flow style.")
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def echo(ctx: click.Context, name: str, **options: Any) -> None:
    """ROS 2: print the introspection events of a service (its SERVICE/_service_event topic), as ros2
    service echo does: REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED. The service and
    its clients must have introspection on (configure_introspection), else nothing is published.

    \b
    Examples:
      rostool --ros2 service echo /add_two_ints
      rostool --ros2 service echo /add_two_ints --no-arr --once
    """
    from rostool.commands.topic import echo as topic_echo

    if ctx.find_root().obj is not None and getattr(ctx.find_root().obj, "ros_version", None) == 1:
        raise RostoolError("service echo applies to ROS 2 graphs (ROS 1 services have no event topic)")
    event_topic = name.rstrip("/") + "/_service_event"
    ctx.invoke(topic_echo, name=event_topic, **options)


@service.command("call", context_settings={"ignore_unknown_options": True})  # negative numbers are values
@click.argument("name", metavar="SERVICE")
@click.argument("values", nargs=-1)
@click.option("--wait", is_flag=True, help="Wait for the service to be advertised first.")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    help="Give up after S seconds (waiting, connecting and the call itself).",
)
@click.option("-r", "--rate", type=click.FloatRange(min=0, min_open=True), metavar="HZ",
              help="ROS 2: call again at HZ until Ctrl+C (as ros2 service call -r).")  # fmt: skip
@click.option("--stdin", "from_stdin", is_flag=True, help="Read the request (YAML) from standard input.")
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def call(
    ctx: click.Context,
    name: str,
    values: tuple[str, ...],
    wait: bool,
    timeout: float | None,
    rate: float | None,
    from_stdin: bool,
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
      rostool --ros2 service call -r 1 /add_two_ints example_interfaces/srv/AddTwoInts "{a: 1, b: 2}"
    """
    from rostool.output.plain import to_plain
    from rostool.output.yaml_text import to_yaml

    if from_stdin:
        values = (*values, sys.stdin.read())
    with live_graph(ctx, interface_paths) as graph:
        if rate is not None and graph.style == "ros1":
            raise RostoolError("service call -r applies to ROS 2 graphs only (ros2 service call's form)")
        lookup = _field_lookup(graph)
        while True:
            started = time.monotonic()
            request, response = graph.service_call(name, values, wait, timeout)
            if as_json:
                print_json(to_plain(response, graph.style))
            elif graph.style == "ros1":
                click.echo(to_yaml(response))
            else:
                click.echo(f"requester: making request: {message_repr(request, lookup)}\n")
                click.echo(f"response:\n{message_repr(response, lookup)}\n", nl=True)
            if rate is None:
                return
            time.sleep(max(0.0, 1.0 / rate - (time.monotonic() - started)))


def _field_lookup(graph: Any) -> Any:
    from rostool.output.ros2_echo import fielddefs_lookup

    return fielddefs_lookup(getattr(getattr(graph.types, "store", None), "fielddefs", {}))
