"""`rostool param describe`: ros2 param describe (type, description, constraints)."""

from __future__ import annotations

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.commands.param._shared import ros2_param_options
from rostool.errors import RostoolError


@click.command("describe")
@click.argument("node")
@click.argument("names", nargs=-1, required=True, metavar="PARAM...")
@ros2_param_options
@json_option
@click.pass_context
def describe(
    ctx: click.Context, node: str, names: tuple[str, ...], include_hidden: bool, node_timeout: float,
    as_json: bool,
) -> None:  # fmt: skip
    """ROS 2: show a parameter's type, description and constraints.

    \b
    Example:
      rostool --ros2 param describe /talker use_sim_time
    """
    from rostool.graph.node_params import find_node

    with live_graph(ctx) as graph:
        if graph.style != "ros2":
            raise RostoolError("param describe applies to ROS 2 parameters (rosparam has no descriptors)")
        params = graph.parameters(find_node(graph, node, include_hidden, node_timeout))
        rows = [params.descriptor(name) for name in names]
    if as_json:
        print_json(rows)
        return
    for row in rows:
        lines = [f"Parameter name: {row['name']}", f"  Type: {row['type']}"]
        if row["description"]:
            lines.append(f"  Description: {row['description']}")
        lines.append("  Constraints:")
        if row["read_only"]:
            lines.append("    Read only: true")
        if row["additional_constraints"]:
            lines.append(f"    {row['additional_constraints']}")
        click.echo("\n".join(lines))
