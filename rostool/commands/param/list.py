"""`rostool param list`: rosparam list's form (NAMESPACE), ros2 param list's (NODE or every node,
--param-prefixes, --filter, -t)."""

from __future__ import annotations

import re

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.param._shared import ros2_only, ros2_param_options
from rostool.errors import RostoolError
from rostool.graph.base import Graph, Parameters


@click.command("list")
@click.argument("namespace", required=False, metavar="[NAMESPACE|NODE]")
@click.option("--param-prefixes", "prefixes", multiple=True, metavar="PREFIX",
              help="ROS 2: only parameters named PREFIX or PREFIX.* (repeatable).")  # fmt: skip
@click.option("-t", "--param-type", "with_types", is_flag=True, help="ROS 2: each name with its type.")
@click.option("--filter", "pattern", metavar="REGEX", help="ROS 2: only names matching REGEX.")
@click.option("--service-timeout", type=click.FloatRange(min=0), hidden=True)
@ros2_param_options
@json_option
@click.pass_context
def list_params(
    ctx: click.Context, namespace: str | None, prefixes: tuple[str, ...], with_types: bool,
    pattern: str | None, service_timeout: float | None, include_hidden: bool, node_timeout: float,
    as_json: bool,
) -> None:  # fmt: skip
    """List parameter names, optionally only under NAMESPACE (ROS 2: of NODE, or of every node).

    \b
    Examples:
      rostool param list /robot
      rostool --ros2 param list /talker -t --filter 'use_.*'
      rostool --ros2 param list --param-prefixes qos_overrides
    """
    from rostool.graph.node_params import find_node

    try:
        regex = re.compile(pattern) if pattern else None
    except re.error as err:
        raise RostoolError(f"--filter {pattern!r} is not a regular expression: {err}") from err
    with live_graph(ctx) as graph:
        ros2_only(graph, param_prefixes=prefixes, param_type=with_types, filter=pattern,
                  include_hidden_nodes=include_hidden)  # fmt: skip
        if graph.style == "ros2":
            wait = max(node_timeout, service_timeout or 0.0)
            node = None if namespace in (None, "/") else find_node(graph, namespace, include_hidden, wait)
            _list_ros2(graph, node, _Selection(prefixes, regex, with_types), include_hidden, as_json)
            return
        names = graph.parameters(namespace or "/").names()
    if as_json:
        print_json(names)
    else:
        for name in names:
            click.echo(name)


class _Selection:
    """ros2 param list's --param-prefixes, --filter and --param-type."""

    def __init__(self, prefixes: tuple[str, ...], regex: re.Pattern[str] | None, with_types: bool) -> None:
        self.prefixes, self.regex, self.with_types = prefixes, regex, with_types

    def names(self, params: Parameters) -> list[str]:
        names = params.names()
        if self.prefixes:  # as rclpy's list_parameters: the prefix itself or PREFIX.anything
            names = [n for n in names if any(n == p or n.startswith(p + ".") for p in self.prefixes)]
        return [n for n in names if self.regex is None or self.regex.match(n)]

    def lines(self, params: Parameters, names: list[str]) -> list[str]:
        if not self.with_types:
            return [f"  {n}" for n in names]
        return [f"  {n} (type: {params.descriptor(n)['type']})" for n in names]


def _list_ros2(
    graph: Graph, node: str | None, selection: _Selection, include_hidden: bool, as_json: bool
) -> None:
    """ros2 param list's forms: one node's names, or every node's under its name."""
    from rostool.graph.node_params import distinct_nodes

    found: dict[str, tuple[Parameters, list[str]]] = {}
    for node_name in [node] if node else distinct_nodes(graph, include_hidden):
        try:
            params = graph.parameters(node_name, timeout=2.0)
            found[node_name] = (params, selection.names(params))
        except RostoolError:
            if node:
                raise
            continue  # a node without parameter services
    if as_json:
        plain = {n: names for n, (_, names) in found.items()}
        print_json(plain[node] if node else plain)
        return
    for node_name, (params, names) in found.items():
        if node is None:
            click.echo(f"{node_name}:")
        if names:
            click.echo("\n".join(selection.lines(params, names)))
