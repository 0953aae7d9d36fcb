"""The Graph protocol's services, actions, parameters, QoS and bag sources for `Ros2Graph`: thin
wrappers over services.py, actions.py, params.py and dds.py."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.recording import Encoding, Put, subscribed_by
from rostool.graph.ros2 import actions, dds, params
from rostool.graph.ros2_calls import call_service
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.base import GoalWatcher, Received
    from rostool.graph.qos import QosRequest
    from rostool.graph.ros2.graph import Ros2Graph


def ros1_only(what: str) -> RostoolError:
    return RostoolError(
        f"{what}: supported on ROS 1 graphs only in this rostool version; "
        "use --ros1 (or set ROS_MASTER_URI) with a ROS 1 master"
    )


class Ros2Verbs:
    # --- QoS, bag play and record -------------------------------------------------------------
    def use_qos(self: Ros2Graph, qos: QosRequest) -> None:
        if qos.given:
            self.qos_request = dds.QosRequest(qos.profile, qos.reliability, qos.durability, qos.depth)

    def raw_publisher(self: Ros2Graph, topic: str, wire_type: str, latch: bool = False) -> Any:
        return self.publisher(topic, wire_type, latch)

    def record_source(self: Ros2Graph, warn: Callable[[str], None], include_hidden: bool = False) -> Any:
        return Ros2Source(self, warn, include_hidden)

    # --- services -----------------------------------------------------------------------------
    def service_type(self: Ros2Graph, name: str) -> str:
        found = self.find_service_type(name)
        if found is None:
            raise RostoolError(f"unknown service {self.resolve(name)}: no server announces it")
        return found

    def service_uri(self, name: str) -> str:
        raise ros1_only("service uri")

    def service_nodes(self, name: str) -> list[str]:
        raise ros1_only("service node (on ROS 2: service list -n)")

    def service_args(self, name: str) -> str:
        raise ros1_only("service args")

    def find_services(self: Ros2Graph, type_name: str) -> list[str]:
        """ros2 service find: the visible services of a type (`pkg/Name` or `pkg/srv/Name`)."""
        pkg, _, name = type_name.strip().strip("/").rpartition("/")
        wanted = f"{pkg.removesuffix('/srv')}/srv/{name}"
        return [s for s, type_, _nodes in self.services() if type_ == wanted and not hidden_name(s)]

    def service_call(
        self: Ros2Graph, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
    ) -> tuple[Any, Any]:
        return call_service(self, name, values, wait, timeout)

    # --- actions ------------------------------------------------------------------------------
    def actions(self: Ros2Graph) -> list[Any]:
        return actions.list_actions(self)  # type: ignore[return-value]

    def action_info(self: Ros2Graph, name: str, wait: float) -> dict[str, Any]:
        """ros2 action info's facts: the action's type, servers and clients."""
        action = self.resolve(name)
        found = next((a for a in actions.list_actions(self, nodes=True) if a.name == action), None)
        if found is None:
            raise RostoolError(f"unknown action {action}: no server announces it (`rostool action list`)")
        return vars(found)

    def send_goal(
        self: Ros2Graph, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> Any:
        return actions.send_goal(
            self, name, kind, goal, timeout, on_event=watcher.event, on_sent=watcher.sent,
            on_waiting=watcher.waiting, on_cancel=watcher.canceling,
        )  # fmt: skip

    def cancel_goals(self: Ros2Graph, name: str, goal_id: str | None) -> list[Any]:
        return actions.cancel_goals(self, self.resolve(name), goal_id)  # type: ignore[return-value]

    # --- parameters ---------------------------------------------------------------------------
    def parameters(self: Ros2Graph, node: str | None, timeout: float = 5.0) -> NodeParameters:
        if node is None:
            raise RostoolError("ROS 2 parameters belong to nodes: give the NODE first")
        return NodeParameters(self, node, timeout)


class NodeParameters(params.ParameterClient):
    def show(self, name: str) -> tuple[Any, str]:
        value = self.get(name)
        if int(value.type) == params.NOT_SET:
            raise RostoolError(f"parameter {name} is not set on node {self.node}")
        return params.to_python(value), params.describe_value(value)

    def descriptor(self, name: str) -> dict[str, Any]:
        d = self.describe(name)
        return {"name": d.name, "type": params.TYPE_NAMES.get(int(d.type), str(d.type)),
                "description": d.description, "additional_constraints": d.additional_constraints,
                "read_only": bool(d.read_only)}  # fmt: skip

    def dump(self) -> Any:
        return params.dump_document(self)

    def load(self, document: Any, use_wildcard: bool, source: str) -> list[tuple[str, bool, str]]:
        parameters = params.file_parameters(document, self.node, use_wildcard, source)
        return self.set_fields(params.load_fields(self, parameters, source))


class Ros2Source:
    """`bag record`'s source: DDS readers that adapt to the publishers' QoS (or use --qos-*); samples stay
    CDR bytes."""

    encoding: Encoding = "cdr"

    def __init__(self, graph: Ros2Graph, warn: Callable[[str], None], include_hidden: bool = False) -> None:
        self.graph = graph
        self.include_hidden = include_hidden
        self.types = graph.types
        self.store = graph.types.store
        self.warn = warn
        self.resolve = graph.resolve
        graph.warn = warn  # the subscriptions' warnings (incompatible QoS) go to the same place

    def published_topics(self) -> list[str]:
        """Topics with a publisher; hidden ones (a name part starting with `_`) are left out unless asked
        for, as `ros2 bag record -a` does."""
        cache = self.graph.session.cache
        cache.poll()
        writers = [e.ros for e in cache.remote_endpoints() if e.is_writer]
        published = {ros[1] for ros in writers if ros is not None and ros[0] == "topic"}
        return sorted(t for t in published if self.include_hidden or not hidden_name(t))

    def subscribed_topics(self, node: str) -> list[str]:
        return subscribed_by(self.graph, node)

    def subscribe(self, topic: str, put: Put) -> None:
        def on_message(received: Received) -> None:
            put(topic, received.payload, received.type_name)

        self.graph.subscribe(topic, on_message, lambda text: self.warn(f"{topic}: {text}"))

    def describe(self, topic: str, origin: Any) -> dict[str, str]:
        """The bag's view of the topic: its ROS 2 type and whether its publishers latch."""
        endpoints = self.graph.session.cache.remote_endpoints()
        writers = [e for e in endpoints if e.is_writer and e.ros == ("topic", topic)]
        latching = any(e.qos.durability == "transient_local" for e in writers)
        return {"topic": topic, "type": str(origin), "callerid": "", "latching": "1" if latching else "0"}

    def close(self) -> None:
        self.graph.close()
