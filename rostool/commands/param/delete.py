"""`rostool param delete`: rosparam delete's form (NAME), ros2 param delete's (NODE PARAM...)."""

from __future__ import annotations

import click

from rostool.commands._common import live_graph
from rostool.commands.param._shared import report, ros2_only, ros2_only_args, ros2_param_options
from rostool.errors import RostoolError


@click.command("delete")
@click.argument("name")
@click.argument("param_names", nargs=-1, metavar="[PARAM]...")
@ros2_param_options
@click.pass_context
def delete(
    ctx: click.Context, name: str, param_names: tuple[str, ...], include_hidden: bool, node_timeout: float
) -> None:
    """Delete a parameter (or a whole namespace). ROS 2: NODE then PARAM (several: one line each).

    \b
    Examples:
      rostool param delete /wheel_radius
      rostool --ros2 param delete /talker my_param
    """
    from rostool.graph.node_params import find_node

    with live_graph(ctx) as graph:
        ros2_only(graph, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            ros2_only_args(graph, param_names[0] if param_names else None, "rostool param delete NODE PARAM")
            params = graph.parameters(None)
            ok, reason = params.delete(name)
            if not ok:
                raise RostoolError(
                    f"deleting parameter {name} on {params.node} failed: {reason or 'refused'}"
                )
            return
        if not param_names:
            raise RostoolError("ROS 2 parameters belong to a node: rostool param delete NODE PARAM")
        params = graph.parameters(find_node(graph, name, include_hidden, node_timeout))
        failed = 0
        for param_name in param_names:
            ok, reason = params.delete(param_name)
            outcome = "Deleted parameter successfully" if ok else "Deleting parameter failed"
            failed += not report(ok, outcome, reason, param_name, params.node, several=len(param_names) > 1)
    if failed:
        ctx.exit(1)
