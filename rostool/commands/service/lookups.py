"""`rostool service uri`, `node` and `args`: rosservice's one-answer lookups of a service."""

from __future__ import annotations

from collections.abc import Callable

import click

from rostool.commands._common import interfaces_option, live_graph
from rostool.graph.base import Graph


def _lookup(verb: str, help_text: str, answer: Callable[[Graph, str], str], sources: bool) -> click.Command:
    """A verb that prints what `answer(graph, SERVICE)` says (with --interfaces when `sources`)."""

    @click.pass_context
    def run(ctx: click.Context, name: str, interface_paths: tuple[str, ...] = ()) -> None:
        with live_graph(ctx, interface_paths) as graph:
            click.echo(answer(graph, name))

    command = click.argument("name", metavar="SERVICE")(interfaces_option(run) if sources else run)
    return click.command(verb, help=help_text)(command)


uri = _lookup(
    "uri",
    """Print the rosrpc:// address of a service.

    \b
    Example:
      rostool service uri /sum_two_ints
    """,
    lambda graph, name: graph.service_uri(name),
    sources=False,
)
node = _lookup(
    "node",
    """Print the node that provides a service.

    \b
    Example:
      rostool service node /sum_two_ints
    """,
    lambda graph, name: "\n".join(graph.service_nodes(name)),
    sources=False,
)
args = _lookup(
    "args",
    """Print the request field names of a service, in the order `call` takes them.

    \b
    Example:
      rostool service args /sum_two_ints      # a b
    """,
    lambda graph, name: graph.service_args(name),
    sources=True,
)
