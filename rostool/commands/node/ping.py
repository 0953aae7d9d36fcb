"""`rostool node ping`: rosnode ping's replies and times."""

from __future__ import annotations

import time

import click

from rostool.commands._common import live_graph


@click.command("ping")
@click.argument("name")
@click.option("-c", "--count", type=click.IntRange(min=1), help="Ping N times (default: until Ctrl+C).")
@click.pass_context
def ping(ctx: click.Context, name: str, count: int | None) -> None:
    """Check that a node answers, and how fast.

    \b
    Example:
      rostool node ping /hello_world_pub_node -c 3
    """
    with live_graph(ctx) as graph:
        uri = graph.node_uri(name)
        click.echo(f"rosnode: node is [{name}]")
        click.echo(f"pinging {name} with a timeout of 3.0s")
        done = 0
        while count is None or done < count:
            if done:
                time.sleep(1.0)
            millis = graph.ping(name)
            click.echo(f"xmlrpc reply from {uri}\ttime={millis:f}ms")
            done += 1
