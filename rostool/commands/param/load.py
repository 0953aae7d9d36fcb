"""`rostool param load`: rosparam load's form (FILE [NAMESPACE]), ros2 param load's (NODE FILE, the '/**'
section too unless --no-use-wildcard)."""

from __future__ import annotations

import sys
from typing import Any

import click

from rostool.commands._common import live_graph
from rostool.commands.param._shared import read_text, ros2_only, ros2_param_options
from rostool.errors import RostoolError


@click.command("load")
@click.argument("file", metavar="FILE|NODE")
@click.argument("namespace", required=False, metavar="[NAMESPACE|FILE]")
@click.option(
    "--no-use-wildcard", is_flag=True, help="ROS 2: skip the file's '/**' section, load only the node's own."
)
@click.option("--use-wildcard", is_flag=True, hidden=True)  # newer ros2cli's spelling of the default
@ros2_param_options
@click.pass_context
def load(
    ctx: click.Context, file: str, namespace: str | None, no_use_wildcard: bool, use_wildcard: bool,
    include_hidden: bool, node_timeout: float,
) -> None:  # fmt: skip
    """Set parameters from a YAML FILE ("-" for stdin), under NAMESPACE.

    ROS 2: NODE then FILE, a parameter file as `param dump` writes it; the node's own section and the
    '/**' section for every node are loaded, the node's own winning.

    \b
    Examples:
      rostool param load params.yaml /robot
      rostool --ros2 param load /talker talker.yaml
      rostool --ros2 param load /talker common.yaml --no-use-wildcard
    """
    from rostool.graph.node_params import find_node

    if use_wildcard and no_use_wildcard:
        raise RostoolError("give --use-wildcard or --no-use-wildcard, not both")
    with live_graph(ctx) as graph:
        node = namespace or "/"
        ros2_only(graph, no_use_wildcard=no_use_wildcard, use_wildcard=use_wildcard,
                  include_hidden_nodes=include_hidden)  # fmt: skip
        if graph.style == "ros2":
            if namespace is None:
                raise RostoolError("ROS 2 parameters belong to a node: rostool param load NODE FILE")
            node, file = find_node(graph, file, include_hidden, node_timeout), namespace
        results = graph.parameters(node).load(_read_document(file), not no_use_wildcard, file)
    for name, ok, reason in results:
        line = f"Set parameter {name} {'successful' if ok else 'failed'}" + (f": {reason}" if reason else "")
        click.echo(line, err=not ok)
    if not all(ok for _, ok, _ in results):
        ctx.exit(1)


def _read_document(file: str) -> Any:
    from rostool.interfaces.values import parse_yaml

    text = sys.stdin.read() if file == "-" else read_text(file)
    return parse_yaml(text, file)
