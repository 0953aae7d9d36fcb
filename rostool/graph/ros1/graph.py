"""The Graph protocol over a ROS 1 master: `Ros1Core`'s nodes and topics, with services (services.py),
actions (actions.py), the parameter server (parameters.py) and bag play and record as thin wrappers."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from functools import partial
from typing import TYPE_CHECKING, Any, Literal

from rostool.errors import RostoolError
from rostool.graph.base import ActionInfo
from rostool.graph.recording import Encoding, Put, RecordSource, subscribed_by
from rostool.graph.ros1 import actions, services
from rostool.graph.ros1.core import Ros1Core
from rostool.graph.ros1.parameters import ServerParameters
from rostool.interfaces.msgspec import InterfaceError
from rostool.interfaces.srv import load_service

if TYPE_CHECKING:
    from rostool.graph.base import ActionSummary, CancelingGoal, GoalOutcome, GoalWatcher, TopicEndpoint
    from rostool.graph.qos import QosRequest
    from rostool.graph.ros1.topics import Publisher
    from rostool.interfaces.ros1 import Ros1Type


class Ros1Graph(Ros1Core):
    """`Graph` on a ROS 1 master; verbs print as the ROS 1 tools do (style "ros1")."""

    ros_version = 1
    style: Literal["ros1", "ros2"] = "ros1"
    encoding: Encoding = "ros1"

    def use_qos(self, qos: QosRequest) -> None:
        if qos.given:
            raise RostoolError("--qos-* options apply to ROS 2 graphs only: ROS 1 topics have no QoS")

    def topic_endpoints(self, name: str) -> list[TopicEndpoint]:
        raise RostoolError("topic endpoints with GIDs and QoS exist on ROS 2 graphs only")

    # --- bag play and record ------------------------------------------------------------------
    def raw_publisher(self, topic: str, wire_type: Ros1Type, latch: bool = False) -> Publisher:
        return self.node.advertise(topic, wire_type, latch)

    def record_source(self, warn: Callable[[str], None], include_hidden: bool = False) -> RecordSource:
        if include_hidden:
            raise RostoolError("--include-hidden-topics applies to ROS 2 graphs only (ROS 1 hides no topics)")
        return Ros1Source(self)

    # --- services -----------------------------------------------------------------------------
    def services(self) -> list[tuple[str, str | None, list[str]]]:
        """(name, None, server nodes): the master does not know types, asking each server would."""
        return [(name, None, nodes) for name, nodes in services.services(self.master)]

    def service_type(self, name: str) -> str:
        return services.service_info(self.master, name).type

    def service_uri(self, name: str) -> str:
        return services.lookup(self.master, name)

    def service_nodes(self, name: str) -> list[str]:
        resolved = self.resolve(name)
        nodes = next((n for s, _type, n in self.services() if s == resolved), None)
        if not nodes:
            raise RostoolError(
                f"unknown service {resolved}: no node provides it (see `rostool service list`)"
            )
        return nodes

    def service_args(self, name: str) -> str:
        uri = services.lookup(self.master, name)
        return services.service_type(self.master, self.catalog(), name, uri).request_args()

    def service_info(self, name: str) -> dict[str, Any]:
        """rosservice info's facts; `args` is None when no .srv of the type is found."""
        found = services.service_info(self.master, name)
        try:
            args: list[str] | None = load_service(self.catalog(), found.type).request_args().split()
        except InterfaceError:
            args = None
        return {"name": found.name, "node": found.node, "uri": found.uri, "type": found.type,
                "md5sum": found.md5sum, "args": args}  # fmt: skip

    def find_services(self, type_name: str) -> list[str]:
        found = []
        for name, _type, _nodes in self.services():
            try:
                header = services.probe(name, services.lookup(self.master, name), self.master.caller_id)
            except RostoolError:
                continue  # a service that vanished or does not answer is not a match
            if header.get("type") == type_name:
                found.append(name)
        return found

    def service_call(
        self, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
    ) -> tuple[Any, Any]:
        return services.call(self.master, self.catalog(), name, values, wait=wait, timeout=timeout)

    def serve_service(self, name: str, srv_type: str, handler: Callable[[Any], Any]) -> Any:
        raise RostoolError(f"serving {name} ({srv_type}) is done on ROS 2 graphs only")

    # --- actions ------------------------------------------------------------------------------
    def actions(self) -> list[ActionSummary]:
        return actions.list_actions(self)

    def action_info(self, name: str, wait: float) -> ActionInfo:
        """The action's summary and the goals its server reports (None: no status within `wait`)."""
        summary = actions.action_summary(self, name)
        goals = actions.goal_states(self, summary.name, wait)
        return ActionInfo(
            name=summary.name, type=summary.type, servers=summary.servers, clients=summary.clients,
            goals=None if goals is None else [asdict(goal) for goal in goals],
        )  # fmt: skip

    def send_goal(
        self, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> GoalOutcome:
        return actions.send_goal(
            self, self.catalog(), name, kind, goal, timeout,
            on_event=watcher.event, on_sent=watcher.sent, on_waiting=watcher.waiting,
        )  # fmt: skip

    def cancel_goals(self, name: str, goal_id: str | None) -> list[CancelingGoal]:
        """Publish the cancel; actionlib servers do not answer which goals it reached."""
        actions.cancel_goals(self, name, goal_id or "")
        return []

    # --- parameters ---------------------------------------------------------------------------
    def parameters(self, node: str | None, timeout: float = 5.0) -> ServerParameters:
        return ServerParameters(self, node)


class Ros1Source:
    """`bag record`'s source: raw TCPROS subscriptions (md5 `*`), bytes stored with the publisher's own
    connection header."""

    encoding: Encoding = "ros1"

    def __init__(self, graph: Ros1Graph) -> None:
        self.graph = graph
        self.types = graph.types
        self.store = None
        self.resolve = graph.resolve

    def published_topics(self) -> list[str]:
        try:
            return list(self.graph.master.published_topics())
        except RostoolError:
            return []  # the master is away: keep recording what is subscribed (as rosbag does)

    def topics_present(self) -> list[str]:
        return self.published_topics()  # the master's answer is whole at once

    def subscribed_topics(self, node: str) -> list[str]:
        return subscribed_by(self.graph, node)

    def subscribe(self, topic: str, put: Put) -> None:
        self.graph.node.subscribe(topic, partial(put, topic))

    def describe(self, topic: str, origin: Any) -> dict[str, str]:
        header = origin.header
        return {
            "topic": topic,
            "type": header.get("type", "*"),
            "md5sum": header.get("md5sum", "*"),
            "message_definition": header.get("message_definition", ""),
            "callerid": header.get("callerid", origin.publisher_uri),
            "latching": header.get("latching", "0"),
        }

    def close(self) -> None:
        self.graph.close()
