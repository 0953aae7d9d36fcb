"""`topic hz` and `topic bw` over several topics: named ones, or `--all` the graph publishes."""

from __future__ import annotations

import click

from rostool.errors import RostoolError
from rostool.graph.base import Graph

all_topics_option = click.option(
    "--all", "all_topics", is_flag=True,
    help="Every topic that has a publisher now (ROS 2: hidden topics left out, as ros2 topic list does).",
)  # fmt: skip


def require_topics(names: tuple[str, ...], all_topics: bool) -> None:
    """Refused before the graph is opened: nothing to measure."""
    if not names and not all_topics:
        raise RostoolError("no topic to measure: name one or more, or give --all")


def chosen_topics(graph: Graph, names: tuple[str, ...], all_topics: bool) -> list[str]:
    """The resolved names to measure, in the order given (with --all: the graph's, sorted, after them)."""
    chosen = [graph.resolve(n) for n in names]
    if all_topics:
        from rostool.interfaces.names import hidden_name

        published = sorted(t.name for t in graph.topics() if t.publishers)
        if graph.style == "ros2":
            published = [n for n in published if not hidden_name(n)]
        chosen += [n for n in published if n not in chosen]
    require_topics(tuple(chosen), all_topics)
    if not chosen:
        raise RostoolError("--all: no topic has a publisher yet")
    return list(dict.fromkeys(chosen))
