"""`rostool node kill`: ask nodes to shut down (rosnode kill)."""

from __future__ import annotations

import click

from rostool.commands._common import live_graph


@click.command("kill")
@click.argument("names", nargs=-1, required=True, metavar="NODE...")
@click.pass_context
def kill(ctx: click.Context, names: tuple[str, ...]) -> None:
    """Ask nodes to shut down.

    \b
    Example:
      rostool node kill /hello_world_pub_node
    """
    with live_graph(ctx) as graph:
        uris = {n: graph.node_uri(n) for n in names}  # every name checked before any is killed
        click.echo(
            "killing " + names[0] if len(names) == 1 else "killing:\n" + "\n".join(f" * {n}" for n in names)
        )
        for name in uris:
            graph.kill(name)
    click.echo("killed")
