"""The Graph protocol's read-only queries the daemon answers, and how their typed results travel as JSON.

Every query here only reads the graph. Subscriptions are relayed (relay_server.py); whatever else opens
endpoints (pub, call, record, goals, parameters) stays with a backend in the verb's own process.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from typing import Any

from rostool.graph.base import ActionSummary, NodeInfo, TopicInfo


def _same(value: Any) -> Any:
    return value


def _node_info(value: dict[str, Any]) -> NodeInfo:
    pairs = ("publications", "subscriptions", "service_clients")
    fixed = {k: [tuple(p) for p in v] if k in pairs else v for k, v in value.items()}
    fixed["connections"] = []  # ROS 2 nodes have no connection list
    return NodeInfo(**fixed)


def _services(value: list[list[Any]]) -> list[tuple[str, str | None, list[str]]]:
    return [(name, type_, nodes) for name, type_, nodes in value]


def _asdicts(value: list[Any]) -> list[dict[str, Any]]:
    return [asdict(v) if not isinstance(v, dict) else v for v in value]


def _as_dict(value: Any) -> Any:
    return asdict(value) if hasattr(value, "__dataclass_fields__") else value


# method -> (result to JSON in the daemon, JSON to result in the client)
SERVED: dict[str, tuple[Callable[[Any], Any], Callable[[Any], Any]]] = {
    "node_names": (_same, _same),
    "node_uri": (_same, _same),
    "node_info": (_as_dict, _node_info),
    "topics": (_asdicts, lambda value: [TopicInfo(**v) for v in value]),
    "topic_type": (_same, _same),
    "topic_endpoints": (_same, _same),
    "services": (_same, _services),
    "service_type": (_same, _same),
    "find_services": (_same, _same),
    "service_info": (_same, _same),
    "actions": (_asdicts, lambda value: [ActionSummary(**v) for v in value]),
    "action_info": (_as_dict, _same),
}
