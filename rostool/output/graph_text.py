"""`rostool graph` as text: a tree per node (rich on a terminal, plain in a pipe) and Graphviz DOT.

DOT is written here as text (a dozen lines) so `--dot` needs no extra; feed it to any Graphviz viewer.
"""

from __future__ import annotations

import json
from collections.abc import Sized

from rostool.output.graph_model import RosGraph, TopicEdges

# rqt_graph's shapes: nodes are ellipses, topics boxes; services (rostool's addition) diamonds
NODE_SHAPE, TOPIC_SHAPE, SERVICE_SHAPE = "ellipse", "box", "diamond"


def tree_lines(graph: RosGraph) -> list[tuple[int, str, str]]:
    """(depth, kind, text) rows: each node, then what it publishes, subscribes, serves and calls."""
    rows: list[tuple[int, str, str]] = []
    for node in graph.nodes:
        rows.append((0, "node", node))
        for topic in graph.topics:
            if node in topic.publishers:
                rows.append((1, "pub", f"pub {_topic(topic)}{_to(graph, topic.subscribers)}"))
        for topic in graph.topics:
            if node in topic.subscribers:
                peers = ", ".join(topic.publishers) or "(no publishers)"
                rows.append((1, "sub", f"sub {_topic(topic)} <- {peers}"))
        for service in graph.services:
            kind = f" [{service.type}]" if service.type else ""
            if node in service.servers:
                rows.append((1, "srv", f"srv {service.name}{kind}"))
            if node in service.clients:
                rows.append((1, "call", f"call {service.name}{kind} -> {', '.join(service.servers) or '?'}"))
    orphans = [t for t in graph.topics if not t.publishers and not t.subscribers]
    if orphans:
        rows.append((0, "node", "(no publisher known)" if graph.recorded else "(no node in view)"))
        rows.extend((1, "topic", _topic(t)) for t in orphans)
    return rows


def _topic(topic: TopicEdges) -> str:
    count = "" if topic.count is None else f" {topic.count} msg{'s' if topic.count != 1 else ''}"
    return f"{topic.name} [{topic.type}]{count}"


def _to(graph: RosGraph, subscribers: list[str]) -> str:
    if graph.recorded:
        return ""
    return " -> " + (", ".join(subscribers) or "(no subscribers)")


def count(items: Sized, word: str) -> str:
    return f"{len(items)} {word}{'' if len(items) == 1 else 's'}"


def summary(graph: RosGraph) -> str:
    text = f"{count(graph.nodes, 'node')}, {count(graph.topics, 'topic')}"
    return text + (f", {count(graph.services, 'service')}" if graph.services else "")


def plain_text(graph: RosGraph) -> str:
    lines = [summary(graph), *("  " * depth + text for depth, _kind, text in tree_lines(graph))]
    return "\n".join(lines)


def print_rich(graph: RosGraph) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.tree import Tree

    colors = {"pub": "green", "sub": "cyan", "srv": "magenta", "call": "magenta", "topic": "yellow"}
    root = Tree(f"[bold]{escape(summary(graph))}[/bold]")
    branch = root
    for depth, kind, text in tree_lines(graph):
        if depth == 0:
            branch = root.add(f"[bold]{escape(text)}[/bold]")
        else:
            branch.add(f"[{colors.get(kind, 'white')}]{escape(text)}[/]")
    Console(highlight=False).print(root)


def _quote(text: str) -> str:
    return json.dumps(text)  # a DOT ID in double quotes escapes like a JSON string


def dot_text(graph: RosGraph) -> str:
    lines = ["digraph rosgraph {", "  rankdir=LR;"]
    for node in graph.nodes:
        lines.append(f"  {_quote('n:' + node)} [label={_quote(node)}, shape={NODE_SHAPE}];")
    for topic in graph.topics:
        label = _quote(topic.name)
        lines.append(f"  {_quote('t:' + topic.name)} [label={label}, shape={TOPIC_SHAPE}, "
                     f"tooltip={_quote(topic.type)}];")  # fmt: skip
    for service in graph.services:
        lines.append(
            f"  {_quote('s:' + service.name)} [label={_quote(service.name)}, shape={SERVICE_SHAPE}];"
        )
    for source, target in edges(graph):
        lines.append(f"  {_quote(source)} -> {_quote(target)};")
    lines.append("}")
    return "\n".join(lines)


def edges(graph: RosGraph) -> list[tuple[str, str]]:
    """Directed edges between prefixed ids (`n:` node, `t:` topic, `s:` service): data flow, as rqt_graph."""
    found = []
    for topic in graph.topics:
        found += [("n:" + n, "t:" + topic.name) for n in topic.publishers]
        found += [("t:" + topic.name, "n:" + n) for n in topic.subscribers]
    for service in graph.services:
        found += [("n:" + n, "s:" + service.name) for n in service.clients]
        found += [("s:" + service.name, "n:" + n) for n in service.servers]
    return found
