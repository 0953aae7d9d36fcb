"""ROS 2 lifecycle nodes (lifecycle_msgs' services `<node>/get_state`,
`get_available_transitions`, `get_transition_graph`, `change_state`), on any ROS 2 backend through the
Graph protocol's `services()`, `node_names()` and `service_call()`.

Which nodes are lifecycle nodes, and which transitions a `set` may name, follow ros2lifecycle (ros2cli):
a node is one when it serves `<node>/get_state` of type lifecycle_msgs/srv/GetState.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from typing import Any

from rostool.errors import RostoolError
from rostool.interfaces.names import hidden_name

GET_STATE = "lifecycle_msgs/srv/GetState"
CHANGE_STATE = "lifecycle_msgs/srv/ChangeState"
GET_TRANSITIONS = "lifecycle_msgs/srv/GetAvailableTransitions"
USER_TRANSITIONS = ("configure", "cleanup", "activate", "deactivate", "shutdown")


@dataclass(frozen=True)
class Transition:
    id: int
    label: str
    start: str
    goal: str


def require_ros2(graph: Any, what: str) -> None:
    if graph.style != "ros2":
        raise RostoolError(f"{what} is a ROS 2 feature; select a ROS 2 graph with --ros2 (or ROS_VERSION=2)")


def lifecycle_nodes(graph: Any, include_hidden: bool) -> list[str]:
    """The nodes serving `<node>/get_state` as lifecycle_msgs/srv/GetState, sorted (ros2lifecycle's rule:
    hidden nodes, and nodes whose service names are hidden, only with include_hidden)."""
    require_ros2(graph, "lifecycle")
    served = {name for name, type_, _nodes in graph.services() if type_ == GET_STATE}
    return sorted(
        node
        for node in set(graph.node_names())
        if f"{node.rstrip('/')}/get_state" in served
        and (include_hidden or not hidden_name(f"{node.rstrip('/')}/get_state"))
    )


def absolute_node_name(name: str) -> str:
    return name if name.startswith("/") else "/" + name


NODE_WAIT_SECONDS = 3.5  # a Fast DDS participant may answer a newcomer only at its next 3 s announcement


def is_lifecycle_node(graph: Any, node: str, include_hidden: bool) -> bool:
    """Is `node` (absolute) a lifecycle node, as ros2lifecycle decides? A node not (or not fully) seen yet
    is given NODE_WAIT_SECONDS, counted from the first listing's answer (a direct listing can take seconds
    to settle, and one that settled before the node was discovered must not be the last one asked), to show
    up with its services."""
    deadline: float | None = None
    while True:
        if node in lifecycle_nodes(graph, include_hidden=True):
            return include_hidden or not hidden_name(f"{node.rstrip('/')}/get_state")
        deadline = deadline or time.monotonic() + NODE_WAIT_SECONDS
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.2)


def _call(graph: Any, node: str, service: str, srv_type: str, request: dict[str, Any] | None = None) -> Any:
    values = (srv_type, json.dumps(request)) if request else (srv_type,)
    _request, response = graph.service_call(f"{node.rstrip('/')}/{service}", values)
    return response


def get_state(graph: Any, node: str) -> tuple[str, int]:
    """(label, id) of the node's current state."""
    state = _call(graph, node, "get_state", GET_STATE).current_state
    return str(state.label), int(state.id)


def transitions(graph: Any, node: str, every: bool = False) -> list[Transition]:
    """The transitions available from the node's current state (every: its whole transition graph)."""
    service = "get_transition_graph" if every else "get_available_transitions"
    response = _call(graph, node, service, GET_TRANSITIONS)
    return [
        Transition(
            int(t.transition.id), str(t.transition.label), str(t.start_state.label), str(t.goal_state.label)
        )
        for t in response.available_transitions
    ]


def change_state(graph: Any, node: str, transition: Transition) -> bool:
    """Trigger a transition; True when the node reports it successful."""
    request = {"transition": {"id": transition.id, "label": transition.label}}
    return bool(_call(graph, node, "change_state", CHANGE_STATE, request).success)
