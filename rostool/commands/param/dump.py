"""`rostool param dump`: rosparam dump's form (FILE [NAMESPACE]), ros2 param dump's (NODE, printed or to
--output-dir)."""

from __future__ import annotations

from pathlib import Path

import click

from rostool.commands._common import json_option, live_graph
from rostool.commands.param._shared import json_text, ros2_only, ros2_param_options, write_text
from rostool.errors import RostoolError


@click.command("dump")
@click.argument("file", metavar="FILE|NODE")
@click.argument("namespace", required=False, metavar="[NAMESPACE|FILE]")
@click.option(
    "--output-dir",
    type=click.Path(),
    metavar="DIR",
    help="ROS 2: write DIR/<node>.yaml (ns/node -> ns__node.yaml) instead of printing; DIR must exist, as "
    "in ros2 param dump.",
)
@click.option(
    "--print", "print_only", is_flag=True, help="ROS 2: print (the default; wins over --output-dir)."
)
@click.option("-a", "--all", "all_nodes", is_flag=True, hidden=True)
@click.option("--service-timeout", type=click.FloatRange(min=0), hidden=True)
@ros2_param_options
@json_option
@click.pass_context
def dump(
    ctx: click.Context, file: str, namespace: str | None, output_dir: str | None, print_only: bool,
    all_nodes: bool, service_timeout: float | None, include_hidden: bool, node_timeout: float, as_json: bool,
) -> None:  # fmt: skip
    """Write parameters (all, or under NAMESPACE) to a YAML FILE ("-" for stdout).

    ROS 2: every parameter of NODE, printed (or written to FILE, or to --output-dir) in the parameter file
    layout that `param load` and a node's --params-file read.

    \b
    Examples:
      rostool param dump params.yaml
      rostool param dump robot.yaml /robot
      rostool --ros2 param dump /talker > talker.yaml
      mkdir -p params && rostool --ros2 param dump /robot/talker --output-dir params/
    """
    from rostool.graph.node_params import find_node
    from rostool.output.yaml_text import param_yaml

    with live_graph(ctx) as graph:
        ros2 = graph.style == "ros2"
        ros2_only(
            graph, output_dir=output_dir, print=print_only, include_hidden_nodes=include_hidden or all_nodes
        )
        if ros2:
            if output_dir and not print_only and not Path(output_dir).is_dir():
                raise RostoolError(f"'{output_dir}' is not a valid directory.")
            node = find_node(graph, file, include_hidden or all_nodes, node_timeout)
            target = namespace or "-"
            if output_dir and not print_only:
                target = str(Path(output_dir) / (node.lstrip("/").replace("/", "__") + ".yaml"))
        else:
            node, target = namespace, file
        document = graph.parameters(node).dump()
    if as_json:
        write_text(target, json_text(document))
    elif ros2 and target == "-":
        click.echo(param_yaml(document))  # ros2 param dump prints the YAML and then a blank line
    else:
        write_text(target, param_yaml(document) if ros2 else param_yaml(document).rstrip("\n") + "\n")
