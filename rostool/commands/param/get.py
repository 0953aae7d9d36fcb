"""`rostool param get`: rosparam get's form (a value or a namespace as YAML), ros2 param get's (NODE PARAM,
NODE PARAM PARAM... as newer ros2cli prints several, or PARAM on every node)."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.param._shared import json_text, ros2_only, ros2_only_args, ros2_param_options
from rostool.errors import RostoolError
from rostool.graph.base import Graph


@click.command("get")
@click.argument("name")
@click.argument("param_names", nargs=-1, metavar="[PARAM]...")
@click.option("--hide-type", is_flag=True, help="ROS 2: print only the value, not its type.")
@ros2_param_options
@json_option
@click.pass_context
def get(
    ctx: click.Context, name: str, param_names: tuple[str, ...], hide_type: bool, include_hidden: bool,
    node_timeout: float, as_json: bool,
) -> None:  # fmt: skip
    """Print a parameter (a namespace prints as a YAML mapping). ROS 2: NODE then PARAM (several: each
    under its name, as ros2cli after Jazzy prints them), or PARAM alone for its value on every node.

    \b
    Examples:
      rostool param get /rosdistro
      rostool --ros2 param get /talker use_sim_time --hide-type
      rostool --ros2 param get /talker use_sim_time start_type_description_service
      rostool --ros2 param get use_sim_time          # every node that has it
    """
    from rostool.graph.node_params import find_node

    with live_graph(ctx) as graph:
        ros2_only(graph, hide_type=hide_type, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            ros2_only_args(graph, param_names[0] if param_names else None, "rostool param get NODE PARAM")
            value, text = graph.parameters(None).show(name)
            click.echo(json_text(value) if as_json else text, nl=not as_json)
            return
        if not param_names and name.startswith("/"):  # a node's name: no parameter name starts so
            raise RostoolError("ROS 2 parameters belong to a node: rostool param get NODE PARAM")
        if not param_names:
            _get_every_node(graph, name, hide_type, include_hidden, as_json)
            return
        node = find_node(graph, name, include_hidden, node_timeout)
        if len(param_names) > 1:
            _get_several(graph, node, param_names, hide_type, as_json)
            return
        value, text = _shown(graph, node, param_names[0], hide_type)
    click.echo(json_text(value) if as_json else text, nl=not as_json)


def _get_several(graph: Graph, node: str, names: tuple[str, ...], hide_type: bool, as_json: bool) -> None:
    """Each parameter under its name (`NAME:` then its line indented; --hide-type: `NAME: value`); a name
    the node does not have fails the whole command, as one GetParameters call does."""
    shown: list[tuple[str, Any, str]] = []
    missing: list[str] = []
    for param in names:
        try:
            shown.append((param, *_shown(graph, node, param, hide_type)))
        except RostoolError:
            missing.append(param)
    if missing:
        quoted = ", ".join(f"'{param}'" for param in dict.fromkeys(missing))
        raise RostoolError(f"Parameter(s) {quoted} not available on node {node}")
    if as_json:
        print_json({param: value for param, value, _ in shown})
        return
    for param, _, text in shown:
        click.echo(f"{param}: {text}" if hide_type else f"{param}:\n  {text}")


def _shown(graph: Graph, node: str, name: str, hide_type: bool) -> tuple[Any, str]:
    from rostool.graph.node_params import shown_param
    from rostool.output.param_text import get_text

    value, text = shown_param(graph, node, name)
    return value, get_text(value, text, hide_type)


def _get_every_node(graph: Graph, name: str, hide_type: bool, include_hidden: bool, as_json: bool) -> None:
    """`param get PARAM`: the value on every node that has it, under the node's name."""
    from rostool.graph.node_params import distinct_nodes

    found: dict[str, tuple[Any, str]] = {}
    for node in distinct_nodes(graph, include_hidden):
        try:
            found[node] = _shown(graph, node, name, hide_type)
        except RostoolError:
            continue  # the node has no such parameter, or no parameter services
    if as_json:
        print_json({node: value for node, (value, _) in found.items()})
    elif not found:
        click.echo(f"Parameter '{name}' not set on any node")
    for node, (_, text) in found.items() if not as_json else ():
        click.echo(f"{node}:\n  {text}")
