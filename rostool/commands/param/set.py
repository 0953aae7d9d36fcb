"""`rostool param set`: rosparam set's form (NAME VALUE), ros2 param set's (NODE, then PARAM VALUE pairs)."""

from __future__ import annotations

import click

from rostool.commands._common import live_graph
from rostool.commands.param._shared import read_text, report, ros2_only, ros2_only_args, ros2_param_options
from rostool.errors import RostoolError


@click.command("set", context_settings={"ignore_unknown_options": True})
@click.argument("name")
@click.argument("value")
@click.argument("more", nargs=-1, metavar="[VALUE2] [PARAM VALUE]...")
@click.option("-t", "--textfile", is_flag=True, help="VALUE is a file whose text becomes a string parameter.")
@ros2_param_options
@click.pass_context
def set_(
    ctx: click.Context, name: str, value: str, more: tuple[str, ...], textfile: bool, include_hidden: bool,
    node_timeout: float,
) -> None:  # fmt: skip
    """Set a parameter; VALUE is YAML, so 0.05 is a float, 5 an int, true a bool, [1, 2] a list.

    ROS 2: NODE, then PARAM VALUE pairs (several pairs print one line each, prefixed by the name).

    \b
    Examples:
      rostool param set /wheel_radius 0.05
      rostool param set /robot "{name: r2, wheels: 4}"
      rostool param set /label "'42'"        # the string "42"
      rostool --ros2 param set /talker use_sim_time true
      rostool --ros2 param set /talker rate 5 label r2
    """
    from rostool.graph.node_params import find_node
    from rostool.interfaces.values import parse_yaml

    with live_graph(ctx) as graph:
        ros2_only(graph, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            ros2_only_args(graph, more[0] if more else None, "rostool param set NODE PARAM VALUE")
            parsed = read_text(value) if textfile else parse_yaml(value, f"the value of {name}")
            params = graph.parameters(None)
            ok, reason = params.set(name, parsed)
            if not ok:
                raise RostoolError(f"setting parameter {name} on {params.node} failed: {reason or 'refused'}")
            return
        pairs = (value, *more)
        if not more or len(pairs) % 2:
            raise RostoolError("ROS 2 parameters belong to a node: give NODE, then name/value pairs")
        node = find_node(graph, name, include_hidden, node_timeout)
        params = graph.parameters(node)
        failed = 0
        for param_name, text in zip(pairs[::2], pairs[1::2], strict=True):
            parsed = read_text(text) if textfile else parse_yaml(text, f"the value of {param_name}")
            ok, reason = params.set(param_name, parsed)
            outcome = "Set parameter successful" if ok else "Setting parameter failed"
            failed += not report(ok, outcome, reason, param_name, params.node, several=len(pairs) > 2)
    if failed:
        ctx.exit(1)
