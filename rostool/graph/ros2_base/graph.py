"""The Graph protocol on ROS 2, written once over a transport: `Ros2Base` assembles listings from the
endpoints the transport describes, wraps its writers as publishers, and carries services, actions,
parameters and bag sources on its service clients and subscriptions. The DDS backend (`graph/ros2/`) and
the rclpy backend (`graph/rclpy/`) subclass it and provide only the methods under "transport"."""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

from rostool.errors import RostoolError
from rostool.graph.base import (
    ActionInfo,
    NodeInfo,
    OnError,
    OnMessage,
    Subscription,
    TopicEndpoint,
    TopicInfo,
)
from rostool.graph.ros2_base import actions
from rostool.graph.ros2_base.calls import call_service, service_info_facts
from rostool.graph.ros2_base.env import domain_id
from rostool.graph.ros2_base.names import resolve
from rostool.graph.ros2_base.params import NodeParameters
from rostool.graph.ros2_base.publisher import Ros2Publisher
from rostool.graph.ros2_base.qos import QosProfile, QosRequest
from rostool.graph.ros2_base.recording import Ros2Source
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.base import CancelingGoal, GoalOutcome, GoalWatcher, ServedService, ServiceInfo
    from rostool.graph.qos import QosRequest as UserQos
    from rostool.graph.recording import Encoding
    from rostool.graph.ros2_base.transport import EndpointView, ServiceClient, ServiceEndpoint, Writer
    from rostool.interfaces.ros2_types import Ros2Types

NodeEndpoints = tuple[set[tuple[str, str]], set[tuple[str, str]], set[tuple[str, str]], set[tuple[str, str]]]


def ros1_only(what: str) -> RostoolError:
    return RostoolError(
        f"{what}: supported on ROS 1 graphs only in this rostool version; "
        "use --ros1 (or set ROS_MASTER_URI) with a ROS 1 master"
    )


class Ros2Base:
    """One ROS 2 graph. Read-only verbs wait for discovery as the transport does; subscribing and publishing
    add endpoints to rostool's own node, `/<node_name>_<pid>`."""

    ros_version = 2
    style: Literal["ros1", "ros2"] = "ros2"
    encoding: Encoding = "cdr"
    types: Ros2Types
    # a direct listing that waits seconds whatever the graph (a discovery floor) lets the graph daemon start
    # beside it: the daemon's start-up then costs this process nothing and the next call finds it sooner
    waits_long = False

    def __init__(
        self,
        node_name: str = "rostool",
        distro: str | None = None,
        anonymous: bool = True,
        interface_paths: Sequence[str] = (),
    ) -> None:
        domain_id()  # a bad ROS_DOMAIN_ID fails in one line before anything starts
        self.qos_request = QosRequest()
        self.warn: Callable[[str], None] = lambda text: print(f"WARNING: {text}", file=sys.stderr)
        base = node_name.strip("/")
        self._node_name = f"{base}_{os.getpid()}" if anonymous else base
        self._lock = threading.Lock()
        self._subscriptions: list[Subscription] = []
        self._served: list[ServedService] = []  # serve_service's, ended before the transport
        self.require_peers = True  # False: an empty graph lists nothing instead of failing (the daemon)
        self.interface_paths = tuple(interface_paths)
        self._prepare(distro)

    # --- transport: what each backend provides ---------------------------------------------------
    def _prepare(self, distro: str | None) -> None:
        """Check the transport's settings and make its type support for `distro` (None: the one found);
        the transport itself starts on first need."""
        raise NotImplementedError

    def _start(self) -> None:
        """Join the graph now (not later, in a subscription's thread)."""
        raise NotImplementedError

    def _close_transport(self) -> None:
        raise NotImplementedError

    def _listing(self, nodes: bool = False) -> None:
        """Wait for discovery as a listing needs it (with `nodes`: until participants named their nodes);
        fail when nothing answers and peers are required."""
        raise NotImplementedError

    def _all_topic_views(self) -> Iterable[tuple[str, EndpointView]]:
        """(topic, endpoint) of every topic's remote endpoints, writers of a topic before its readers."""
        raise NotImplementedError

    def topic_views(self, topic: str) -> list[EndpointView]:
        """The remote endpoints of one topic, writers first, as the transport knows them now."""
        raise NotImplementedError

    def _await_topic(self, topic: str) -> None:
        """Wait (a moment) for `topic` to have a publisher: `topic_type` asks then."""
        raise NotImplementedError

    def _node_endpoints(self, node: str) -> NodeEndpoints:
        """(publications, subscriptions, served services, called services) of a node, as (name, type)."""
        raise NotImplementedError

    def _service_endpoint_views(self, service: str) -> Iterable[ServiceEndpoint]:
        raise NotImplementedError

    def _writer(self, topic: str, store_name: str, profile: QosProfile) -> Writer:
        raise NotImplementedError

    def _subscription(
        self, topic: str, on_message: OnMessage, on_error: OnError,
        request: QosRequest | None = None, warn: Callable[[str], None] | None = None,
        type_name: str | None = None,
    ) -> Subscription:  # fmt: skip
        """The transport's subscription; `request` and `warn` are the graph's unless given; `type_name` (a
        store name) subscribes at once with that type instead of waiting for a publisher to tell it."""
        raise NotImplementedError

    def _service_server(self, service: str, srv_type: str, answer: Callable[[Any], Any]) -> ServedService:
        """Serve `service` from this process's node: `answer(request message) -> response message`, called
        on a thread of the transport; raises RostoolError when the transport cannot serve the type."""
        raise NotImplementedError

    def store_name(self, type_name: str) -> str:
        """`pkg/Type` or `pkg/msg/Type` -> `pkg/msg/Type`, known to rosbags' store."""
        raise NotImplementedError

    def node_names(self) -> list[str]:
        raise NotImplementedError

    def node_uri(self, name: str) -> str:
        raise NotImplementedError

    def service_endpoints(self, nodes: bool = False) -> list[tuple[str, str, list[str], list[str]]]:
        """(name, type, server nodes, client nodes) of every service that has a server; with `nodes`,
        once every participant has named its nodes."""
        raise NotImplementedError

    def service_client(self, service: str, srv_type: str) -> ServiceClient:
        raise NotImplementedError

    def published_topics(self) -> set[str]:
        """The topics another process publishes now (`bag record`'s polls)."""
        raise NotImplementedError

    def before_node_check(self) -> None:
        """Before a node's parameter services are looked for."""

    def serves_under(self, prefix: str) -> bool:
        """Whether another process serves a service named `prefix...` now."""
        raise NotImplementedError

    def announces_node(self, node: str) -> bool:
        raise NotImplementedError

    def wait_for_discovery(self) -> None:
        raise NotImplementedError

    def wait_for_newcomers(self, limit: float = 1.0) -> None:
        raise NotImplementedError

    def send_goal(
        self, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> GoalOutcome:
        raise NotImplementedError

    # --- the graph ---------------------------------------------------------------------------------
    @property
    def node_name(self) -> str:
        return "/" + self._node_name

    def __enter__(self) -> Ros2Base:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def close(self) -> None:
        for sub in self._subscriptions:
            sub.close()
        self._subscriptions.clear()
        for served in self._served:
            served.close()
        self._served.clear()
        self._close_transport()

    def resolve(self, name: str) -> str:
        return resolve(name)

    def use_qos(self, qos: UserQos) -> None:
        if qos.given:
            self.qos_request = QosRequest.of(qos)

    # --- nodes ---------------------------------------------------------------------------------------
    def node_info(self, name: str) -> NodeInfo:
        resolved = resolve(name)
        uri = self.node_uri(resolved)
        pubs, subs, servers, clients = self._node_endpoints(resolved)
        info = NodeInfo(resolved, uri, None, sorted(pubs), sorted(subs), sorted({s for s, _ in servers}), [])
        info.service_types = dict(sorted(servers))
        info.service_clients = sorted(clients)
        return info

    def ping(self, name: str) -> float:
        raise RostoolError("ROS 2 nodes cannot be pinged (there is no node API); try `rostool node info`")

    def kill(self, name: str) -> None:
        raise RostoolError("ROS 2 nodes cannot be killed remotely (there is no node API); stop the process")

    # --- topics --------------------------------------------------------------------------------------
    def topics(self) -> list[TopicInfo]:
        self._listing()
        found: dict[str, TopicInfo] = {}
        for topic, view in self._all_topic_views():
            info = found.setdefault(topic, TopicInfo(topic, view.type_name))
            (info.publishers if view.is_writer else info.subscribers).append(view.node)
        for info in found.values():
            info.publishers.sort()
            info.subscribers.sort()
        return [found[name] for name in sorted(found)]

    def topic_endpoints(self, name: str) -> list[TopicEndpoint]:
        """Every remote reader and writer of a topic with its node, type, GID and QoS (topic info -v)."""
        resolved = resolve(name)
        self._listing(nodes=True)
        rows: list[TopicEndpoint] = [
            {
                "node": view.node, "endpoint_type": "PUBLISHER" if view.is_writer else "SUBSCRIPTION",
                "type": view.type_name, "type_hash": view.type_hash, "gid": view.gid,
                "qos": view.qos.endpoint_facts(),
            }
            for view in self.topic_views(resolved)
        ]  # fmt: skip
        return sorted(rows, key=lambda r: (r["endpoint_type"] != "PUBLISHER", r["node"]))

    def topic_type(self, name: str) -> str | None:
        resolved = resolve(name)
        self._await_topic(resolved)
        views = self.topic_views(resolved)
        return views[0].type_name if views else None

    def subscribe(
        self, topic: str, on_message: OnMessage, on_error: OnError | None = None, type_name: str | None = None
    ) -> Subscription:
        """`type_name` (known to the store: `store_name()`): subscribe at once with it (bag record's static
        topics), not once a publisher shows the topic's type."""
        self._start()
        sub = self._subscription(resolve(topic), on_message, on_error or self.warn, type_name=type_name)
        self._subscriptions.append(sub)
        return sub

    def publisher(
        self, topic: str, type_name: str, latch: bool = False, existing: str | None = None
    ) -> Ros2Publisher:
        """A publisher of `type_name`, refused when the topic has another type: `existing` (a graph
        daemon's answer), else whatever discovery knows at once (publishing never waits for a settle)."""
        resolved = resolve(topic)
        store_name = self.store_name(type_name)
        if existing is None:
            views = self.topic_views(resolved)
            existing = views[0].type_name if views else None
        if existing and existing != store_name:
            raise RostoolError(
                f"topic {resolved} already has type {existing}; cannot publish {store_name} on it"
            )
        request = self.qos_request
        base = request.base()
        if latch and request.durability is None:
            base = QosProfile(base.reliability, "transient_local", base.depth)
        writer = self._writer(resolved, store_name, request.apply(base))
        return Ros2Publisher(resolved, store_name, writer, self.types)

    def message_class(self, type_name: str) -> type:
        return self.types.store.types[self.store_name(type_name)]  # type: ignore[no-any-return]

    def build_message(self, type_name: str, value: Any) -> Any:
        from rostool.interfaces.fill import build_message

        store_name = self.store_name(type_name)
        return build_message(self.types.store, store_name, self.types.with_defaults(store_name, value))

    # --- bag play and record -------------------------------------------------------------------------
    def raw_publisher(self, topic: str, wire_type: Any, latch: bool = False) -> Ros2Publisher:
        return self.publisher(topic, str(wire_type), latch)

    def record_source(self, warn: Callable[[str], None], include_hidden: bool = False) -> Ros2Source:
        return Ros2Source(self, warn, include_hidden)

    # --- services ------------------------------------------------------------------------------------
    def services(self) -> list[tuple[str, str | None, list[str]]]:
        """(name, type, server nodes) of every service another node serves."""
        return [(name, type_, servers) for name, type_, servers, _clients in self.service_endpoints()]

    def find_service_type(self, service: str) -> str | None:
        """The type a server of `service` announces (`pkg/srv/Name`), None when no server is seen."""
        resolved = resolve(service)
        return next((type_ for name, type_, _nodes in self.services() if name == resolved), None)

    def service_type(self, name: str) -> str:
        found = self.find_service_type(name)
        if found is None:
            raise RostoolError(f"unknown service {self.resolve(name)}: no server announces it")
        return found

    def find_services(self, type_name: str) -> list[str]:
        """ros2 service find: the visible services of a type (`pkg/Name` or `pkg/srv/Name`)."""
        pkg, _, name = type_name.strip().strip("/").rpartition("/")
        wanted = f"{pkg.removesuffix('/srv')}/srv/{name}"
        return [s for s, type_, _nodes in self.services() if type_ == wanted and not hidden_name(s)]

    def service_info(self, service: str) -> ServiceInfo | None:
        """ros2 service info's facts: the service's types, its clients and its servers (each with node, type
        hash, the GIDs and QoS of its two DDS endpoints); None when no client or server announces it."""
        resolved = resolve(service)
        self._listing(nodes=True)
        return service_info_facts(resolved, self._service_endpoint_views(resolved))

    def service_call(
        self, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
    ) -> tuple[Any, Any]:
        return call_service(self, name, values, wait, timeout)

    def serve_service(
        self, name: str, srv_type: str, handler: Callable[[Any], Mapping[str, Any]]
    ) -> ServedService:
        """Serve `name` (`pkg/srv/Type`: the store's, a built-in or a source definition) from this process's
        node until closed; `handler(request)` returns the response's fields (the rest keep their defaults)."""
        from rostool.interfaces.fill import build_message
        from rostool.interfaces.ros2_srv import register_service

        _request_type, response_type = register_service(self.types, srv_type)
        types = self.types

        def answer(request: Any) -> Any:
            try:
                fields = dict(handler(request))
            except Exception as err:  # a failing handler must not stop the serving thread
                self.warn(f"{name}: cannot answer: {err}")
                fields = {}
            return build_message(types.store, response_type, types.with_defaults(response_type, fields))

        self._start()
        served = self._service_server(resolve(name), srv_type, answer)
        self._served.append(served)
        return served

    def service_uri(self, name: str) -> str:
        raise ros1_only("service uri")

    def service_nodes(self, name: str) -> list[str]:
        raise ros1_only("service node (on ROS 2: service list -n)")

    def service_args(self, name: str) -> str:
        raise ros1_only("service args")

    # --- actions -------------------------------------------------------------------------------------
    def actions(self) -> list[actions.ActionSummary]:
        return actions.list_actions(self)

    def action_info(self, name: str, wait: float) -> ActionInfo:
        """ros2 action info's facts: the action's type, servers and clients."""
        action = self.resolve(name)
        found = next((a for a in actions.list_actions(self, nodes=True) if a.name == action), None)
        if found is None:
            raise RostoolError(f"unknown action {action}: no server announces it (`rostool action list`)")
        return {"name": found.name, "type": found.type, "servers": found.servers, "clients": found.clients}

    def cancel_goals(self, name: str, goal_id: str | None) -> list[CancelingGoal]:
        return actions.cancel_goals(self, name, goal_id)

    # --- parameters ----------------------------------------------------------------------------------
    def parameters(self, node: str | None, timeout: float = 5.0) -> NodeParameters:
        if node is None:
            raise RostoolError("ROS 2 parameters belong to nodes: give the NODE first")
        return NodeParameters(self, node, timeout)
