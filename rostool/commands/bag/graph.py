"""`rostool bag graph`: a bag's topics and types, and (ROS 1 bags) the nodes that published them."""

from __future__ import annotations

from pathlib import Path

import click

from rostool.commands.graph import CONTEXT, check_options, output_option, render


@click.command(context_settings=CONTEXT)
@click.argument("bags", nargs=-1, required=True, metavar="BAG...")
@click.option("--dot", "as_dot", is_flag=True, help="Print Graphviz DOT.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON for scripts.")
@output_option
def graph(bags: tuple[str, ...], as_dot: bool, as_json: bool, output: Path | None) -> None:
    """Show a bag's topics with their types as a graph; for ROS 1 bags with the publishing node of each
    connection (the callerid rosbag record stored). Same outputs as `rostool graph`.

    \b
    Examples:
      rostool bag graph run.bag
      rostool bag graph run.bag -o run.svg
      rostool bag graph rosbag2_dir --json
    """
    from rostool.bag.reader import BagReader
    from rostool.output.graph_model import from_bag

    check_options(as_dot, as_json, output)
    with BagReader(list(bags)) as reader:
        found = from_bag(reader)
    render(found, as_dot, as_json, output)
