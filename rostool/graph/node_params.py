"""ros2 param's lookups over the `Graph` protocol: a node by name (hidden ones on request, waiting for it to
appear), every node once, a parameter's value and text (a declared but unset one included)."""

from __future__ import annotations

import time
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import Graph
from rostool.interfaces.names import hidden_name


def find_node(graph: Graph, node: str, include_hidden: bool, timeout: float) -> str:
    """ros2 param's node check: a hidden node needs --include-hidden-nodes; wait up to TIMEOUT for it."""
    resolved = graph.resolve(node)
    if hidden_name(resolved) and not include_hidden:
        raise RostoolError(f"Node not found: {resolved} is hidden (add --include-hidden-nodes)")
    # the timeout counts from the first answer: a direct listing can itself take seconds to settle, and
    # a listing that settled before the node was discovered must not be the last one asked
    names = graph.node_names()
    deadline = time.monotonic() + timeout
    while resolved not in names:
        if time.monotonic() >= deadline:
            raise RostoolError(f"Node not found: {resolved} (see `rostool node list`)")
        time.sleep(0.2)
        names = graph.node_names()
    return resolved


def distinct_nodes(graph: Graph, include_hidden: bool) -> list[str]:
    """Each node name once (nodes may share a name; their parameter services are the same names)."""
    return [n for n in dict.fromkeys(graph.node_names()) if include_hidden or not hidden_name(n)]


def shown_param(graph: Graph, node: str, name: str) -> tuple[Any, str]:
    """A parameter's value and ros2 param get's text for it ("Parameter not set." for a declared, unset
    one)."""
    params = graph.parameters(node)
    try:
        return params.show(name)
    except RostoolError:
        try:
            declared_unset = params.descriptor(name)["type"] == "not set"
        except RostoolError:
            declared_unset = False
        if not declared_unset:
            raise
        return None, "Parameter not set."
