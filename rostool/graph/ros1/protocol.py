"""The Graph protocol's services, actions, parameters, QoS and bag sources for `Ros1Graph`: thin wrappers
over services.py, actions.py and the master's parameter server."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.recording import Encoding, Put, subscribed_by
from rostool.graph.ros1 import actions, services
from rostool.graph.ros1.master_client import RemoteError

if TYPE_CHECKING:
    from rostool.graph.base import GoalWatcher
    from rostool.graph.qos import QosRequest
    from rostool.graph.ros1.graph import Ros1Graph
    from rostool.graph.ros1.topics import Publisher
    from rostool.interfaces.ros1 import Ros1Type
    from rostool.interfaces.sources import Interfaces


class Ros1Verbs:
    def use_qos(self, qos: QosRequest) -> None:
        if qos.given:
            raise RostoolError("--qos-* options apply to ROS 2 graphs only: ROS 1 topics have no QoS")

    def _catalog(self: Ros1Graph) -> Interfaces:
        from rostool.interfaces.sources import interfaces

        return interfaces(self.interface_paths)

    def topic_endpoints(self, name: str) -> list[dict[str, Any]]:
        raise RostoolError("topic endpoints with GIDs and QoS exist on ROS 2 graphs only")

    # --- bag play and record ------------------------------------------------------------------
    def raw_publisher(self: Ros1Graph, topic: str, wire_type: Ros1Type, latch: bool = False) -> Publisher:
        return self.node.advertise(topic, wire_type, latch)

    def record_source(self: Ros1Graph, warn: Callable[[str], None], include_hidden: bool = False) -> Any:
        if include_hidden:
            raise RostoolError("--include-hidden-topics applies to ROS 2 graphs only (ROS 1 hides no topics)")
        return Ros1Source(self)

    # --- services -----------------------------------------------------------------------------
    def services(self: Ros1Graph) -> list[tuple[str, str | None, list[str]]]:
        """(name, None, server nodes): the master does not know types, asking each server would."""
        return [(name, None, nodes) for name, nodes in services.services(self.master)]

    def service_type(self: Ros1Graph, name: str) -> str:
        return services.service_info(self.master, name).type

    def service_uri(self: Ros1Graph, name: str) -> str:
        return services.lookup(self.master, name)

    def service_nodes(self: Ros1Graph, name: str) -> list[str]:
        resolved = self.resolve(name)
        nodes = next((n for s, _type, n in self.services() if s == resolved), None)
        if not nodes:
            raise RostoolError(
                f"unknown service {resolved}: no node provides it (see `rostool service list`)"
            )
        return nodes

    def service_args(self: Ros1Graph, name: str) -> str:
        uri = services.lookup(self.master, name)
        return services.service_type(self.master, self._catalog(), name, uri).request_args()

    def service_info(self: Ros1Graph, name: str) -> dict[str, Any]:
        """rosservice info's facts; `args` is None when no .srv of the type is found."""
        from rostool.interfaces.sources import InterfaceError
        from rostool.interfaces.srv import load_service

        found = services.service_info(self.master, name)
        try:
            args: list[str] | None = load_service(self._catalog(), found.type).request_args().split()
        except InterfaceError:
            args = None
        return {"name": found.name, "node": found.node, "uri": found.uri, "type": found.type,
                "md5sum": found.md5sum, "args": args}  # fmt: skip

    def find_services(self: Ros1Graph, type_name: str) -> list[str]:
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
        self: Ros1Graph, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
    ) -> tuple[Any, Any]:
        return services.call(self.master, self._catalog(), name, values, wait=wait, timeout=timeout)

    # --- actions ------------------------------------------------------------------------------
    def actions(self: Ros1Graph) -> list[Any]:
        return actions.list_actions(self)  # type: ignore[return-value]

    def action_info(self: Ros1Graph, name: str, wait: float) -> dict[str, Any]:
        """The action's summary and the goals its server reports (None: no status within `wait`)."""
        summary = actions.action_summary(self, name)
        goals = actions.goal_states(self, summary.name, wait)
        return {**vars(summary), "goals": None if goals is None else
                [{"id": g.id, "status": g.status_name, "text": g.text} for g in goals]}  # fmt: skip

    def send_goal(
        self: Ros1Graph, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> Any:
        return actions.send_goal(
            self, self._catalog(), name, kind, goal, timeout,
            on_event=watcher.event, on_sent=watcher.sent, on_waiting=watcher.waiting,
        )  # fmt: skip

    def cancel_goals(self: Ros1Graph, name: str, goal_id: str | None) -> list[Any]:
        """Publish the cancel; actionlib servers do not answer which goals it reached."""
        actions.cancel_goals(self, name, goal_id or "")
        return []

    # --- parameters ---------------------------------------------------------------------------
    def parameters(self: Ros1Graph, node: str | None, timeout: float = 5.0) -> ServerParameters:
        return ServerParameters(self, node)


class ServerParameters:
    """The parameter server in the per-node shape: NODE, when given, is a namespace (as rosparam takes it);
    names are the server's full names."""

    def __init__(self, graph: Ros1Graph, node: str | None) -> None:
        self.master = graph.master
        self.resolve = graph.resolve
        self.node = graph.resolve(node or "/")

    def names(self) -> list[str]:
        ns = self.node
        return [n for n in sorted(self.master.param_names()) if ns in ("/", n) or n.startswith(ns + "/")]

    def value(self, name: str) -> Any:
        name = self.resolve(name)
        try:
            return self.master.get_param(name)
        except RemoteError as err:
            raise RostoolError(f"parameter {name} is not set") from err

    def show(self, name: str) -> tuple[Any, str]:
        from rostool.output.yaml_text import param_yaml

        value = self.value(name)
        return value, param_yaml(value)

    def set(self, name: str, value: Any) -> tuple[bool, str]:
        """Set like rosparam: a mapping updates the namespace key by key instead of replacing it."""
        if isinstance(value, dict):
            for key, item in value.items():
                self.set(key if str(key).startswith("/") else f"{name.rstrip('/')}/{key}", item)
            return True, ""
        try:
            self.master.set_param(self.resolve(name), value)
        except OverflowError as err:
            raise RostoolError(f"{name}: integers must fit in 32 bits on the ROS 1 parameter server") from err
        except TypeError as err:
            why = f"this value cannot be stored on the parameter server ({err})"
            raise RostoolError(f"{name}: {why}") from err
        return True, ""

    def delete(self, name: str) -> tuple[bool, str]:
        name = self.resolve(name)
        try:
            self.master.delete_param(name)
        except RemoteError as err:
            raise RostoolError(f"parameter {name} is not set, nothing to delete") from err
        return True, ""

    def descriptor(self, name: str) -> dict[str, Any]:
        raise RostoolError("param describe applies to ROS 2 nodes (ROS 1 parameters have no descriptors)")

    def dump(self) -> Any:
        return self.value(self.node)

    def load(self, document: Any, use_wildcard: bool, source: str) -> list[tuple[str, bool, str]]:
        """The document under NODE (the namespace); a single value needs a namespace other than /."""
        if document is None:
            raise RostoolError(f"{source} holds no parameters")
        if not isinstance(document, dict) and self.node == "/":
            raise RostoolError(f"{source} holds a single value; give a NAMESPACE to store it under")
        self.set(self.node, document)
        return []


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
