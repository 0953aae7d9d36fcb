"""`topic hz` and `topic bw` over several topics: named ones, or `--all` the graph publishes."""

from __future__ import annotations

import click

from rostool.errors import RostoolError
from rostool.graph.base import Graph

all_topics_option = click.option(
    "--all", "all_topics", is_flag=True,
    help="Every topic that has a publisher now (ROS 2: hidden topics left out, as ros2 topic list does).",
)  # fmt: skip


def chosen_topics(graph: Graph, names: tuple[str, ...], all_topics: bool) -> list[str]:
    """The resolved names to measure, in the order given (with --all: the graph's, sorted, after them)."""
    chosen = [graph.resolve(n) for n in names]
    if all_topics:
        from rostool.interfaces.names import hidden_name

        published = sorted(t.name for t in graph.topics() if t.publishers)
        if graph.style == "ros2":
            published = [n for n in published if not hidden_name(n)]
        chosen += [n for n in published if n not in chosen]
    if not chosen:
        raise RostoolError("no topic to measure: name one or more, or give --all" if not all_topics
                           else "--all: no topic has a publisher yet")  # fmt: skip
    return list(dict.fromkeys(chosen))
