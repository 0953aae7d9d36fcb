"""`rostool graph`: the live node/topic graph as rqt_graph draws it, without Qt (text, DOT, JSON, SVG/PNG)."""

from __future__ import annotations

from pathlib import Path

import click

from rostool.commands._common import live_graph, print_json, stdout_is_tty
from rostool.errors import RostoolError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
DRAWN = (".svg", ".png", ".pdf")


def output_option(func: click.decorators.FC) -> click.decorators.FC:
    return click.option(
        "-o", "--output", type=click.Path(dir_okay=False, path_type=Path), metavar="FILE",
        help="Draw to FILE: .svg, .png or .pdf (needs `pip install 'rostool[plot]'`); .dot or .json write "
        "those texts.",
    )(func)  # fmt: skip


def check_options(as_dot: bool, as_json: bool, output: Path | None) -> None:
    """Refuse what cannot be written before the graph or bag is read."""
    if as_dot and as_json:
        raise RostoolError("choose one of --dot and --json")
    if output is not None and output.suffix.lower() not in (*DRAWN, ".dot", ".gv", ".json"):
        raise RostoolError(f"{output}: unknown format; name the file .svg, .png, .pdf, .dot or .json")


def render(graph: object, as_dot: bool, as_json: bool, output: Path | None) -> None:
    """One graph to the chosen output: a file, DOT, JSON, or the text tree (rich on a terminal)."""
    from rostool.output.graph_model import RosGraph
    from rostool.output.graph_text import dot_text, plain_text, print_rich, summary

    assert isinstance(graph, RosGraph)
    check_options(as_dot, as_json, output)
    if output is not None:
        suffix = output.suffix.lower()
        if suffix in DRAWN:
            from rostool.output.graph_draw import draw

            draw(graph, output)
        elif suffix in (".dot", ".gv"):
            output.write_text(dot_text(graph) + "\n")
        elif suffix == ".json":
            from rostool.output.json_text import dumps

            output.write_text(dumps(graph.as_json()) + "\n")
        else:
            raise RostoolError(f"{output}: unknown format; name the file .svg, .png, .pdf, .dot or .json")
        click.echo(f"wrote {output} ({summary(graph)})", err=True)
    elif as_dot:
        click.echo(dot_text(graph))
    elif as_json:
        print_json(graph.as_json())
    elif stdout_is_tty():
        print_rich(graph)
    else:
        click.echo(plain_text(graph))


@click.command(context_settings=CONTEXT)
@click.option("--services", is_flag=True, help="Also show services (servers; on ROS 2 also their clients).")
@click.option(
    "-a",
    "--all",
    "show_all",
    is_flag=True,
    help="Also show /rosout, /parameter_events, parameter services and hidden (_) names.",
)
@click.option("--ns", metavar="NS", help="Only nodes and topics under NS (and the topics those nodes use).")
@click.option("--dot", "as_dot", is_flag=True, help="Print Graphviz DOT.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON for scripts.")
@output_option
@click.pass_context
def graph(
    ctx: click.Context, services: bool, show_all: bool, ns: str | None, as_dot: bool, as_json: bool,
    output: Path | None,
) -> None:  # fmt: skip
    """Show which nodes publish and subscribe to which topics (rqt_graph without Qt), ROS 1 and ROS 2.

    On a terminal a tree per node; in a pipe the same as plain text; --dot for Graphviz, --json for
    scripts, -o to draw an SVG/PNG/PDF (nodes as rounded boxes, topics as square boxes, data flowing left
    to right). /rosout, /parameter_events and hidden names are left out unless --all.

    \b
    Examples:
      rostool graph
      rostool graph --ns /robot --services
      rostool graph -o graph.svg
      rostool graph --dot | dot -Tpng > graph.png
      rostool --ros2 graph --json
    """
    from rostool.graph.topology import collect

    check_options(as_dot, as_json, output)
    with live_graph(ctx) as live:
        found = collect(live, services=services, show_all=show_all, ns=ns)
    render(found, as_dot, as_json, output)
