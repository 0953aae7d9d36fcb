"""`rostool param get`: rosparam get's form (a value or a namespace as YAML), ros2 param get's (NODE PARAM,
or PARAM on every node)."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.param._shared import json_text, ros2_only, ros2_only_args, ros2_param_options
from rostool.errors import RostoolError
from rostool.graph.base import Graph


@click.command("get")
@click.argument("name")
@click.argument("param_name", required=False, metavar="[PARAM]")
@click.option("--hide-type", is_flag=True, help="ROS 2: print only the value, not its type.")
@ros2_param_options
@json_option
@click.pass_context
def get(
    ctx: click.Context, name: str, param_name: str | None, hide_type: bool, include_hidden: bool,
    node_timeout: float, as_json: bool,
) -> None:  # fmt: skip
    """Print a parameter (a namespace prints as a YAML mapping). ROS 2: NODE then PARAM, or PARAM alone
    for its value on every node.

    \b
    Examples:
      rostool param get /rosdistro
      rostool --ros2 param get /talker use_sim_time --hide-type
      rostool --ros2 param get use_sim_time          # every node that has it
    """
    from rostool.graph.node_params import find_node

    with live_graph(ctx) as graph:
        ros2_only(graph, hide_type=hide_type, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            ros2_only_args(graph, param_name, "rostool param get NODE PARAM")
            value, text = graph.parameters(None).show(name)
            click.echo(json_text(value) if as_json else text, nl=not as_json)
            return
        if param_name is None and name.startswith("/"):  # a node's name: no parameter name starts so
            raise RostoolError("ROS 2 parameters belong to a node: rostool param get NODE PARAM")
        if param_name is None:
            _get_every_node(graph, name, hide_type, include_hidden, as_json)
            return
        node = find_node(graph, name, include_hidden, node_timeout)
        value, text = _shown(graph, node, param_name, hide_type)
    click.echo(json_text(value) if as_json else text, nl=not as_json)


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
