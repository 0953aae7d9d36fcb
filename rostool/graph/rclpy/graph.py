"""The Graph interface over rclpy: the user's own client library and RMW see the graph; rosbags makes and
reads every message byte (subscriptions are raw, publishers publish serialized bytes), so the verbs print
exactly what they print with the DDS backend.

Listing verbs wait until the graph rmw reports stops changing (GRAPH_QUIET_SECONDS after something other
than this process was seen, at most SETTLE_MAX_SECONDS when nothing is), as discovery takes a moment.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Literal

from rostool.errors import RostoolError
from rostool.graph.base import NodeInfo, Received, Subscription, TopicInfo
from rostool.graph.rclpy import types as rtypes
from rostool.graph.rclpy.recording import BagVerbs
from rostool.graph.rclpy.refusals import Refusals
from rostool.graph.rclpy.services import ServiceVerbs
from rostool.graph.rclpy.verbs import ActionVerbs, ParameterVerbs
from rostool.graph.ros2 import dds
from rostool.graph.ros2.names import resolve
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.qos import QosRequest
    from rostool.graph.rclpy.context import RclpyContext
    from rostool.graph.recording import Encoding
    from rostool.interfaces.ros2_types import Ros2Types

GRAPH_QUIET_SECONDS = 0.5
# a direct listing (no daemon) answers no sooner than this: the participants that answer a newcomer's first
# announcements (and their endpoints) keep coming for a second or two, later on a loaded machine; the
# daemon's long-lived graph answers at once
SETTLE_MIN_SECONDS = 2.0
# nothing but ourselves seen: how long before "no nodes found". A Fast DDS participant may answer a new one
# only with its next periodic announcement (every 3 s), so discovery takes from 0 to about 3 s
SETTLE_MAX_SECONDS = 4.5
TOPIC_WAIT_SECONDS = 1.5  # topic_type: how long a topic without publishers is given to get one
UNKNOWN_NODE = "_NODE_NAME_UNKNOWN_"  # what ros2cli (and the DDS backend) show for endpoints of no node


class RclpyGraph(ServiceVerbs, ParameterVerbs, ActionVerbs, BagVerbs, Refusals):
    ros_version = 2
    style: Literal["ros1", "ros2"] = "ros2"
    encoding: Encoding = "cdr"

    def __init__(
        self,
        node_name: str = "rostool",
        distro: str | None = None,
        anonymous: bool = True,
        interface_paths: Sequence[str] = (),
    ) -> None:
        from rostool.graph.rclpy.facts import rclpy_distro
        from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS

        dds.domain_id()  # a bad ROS_DOMAIN_ID fails in one line before rcl sees it
        found = distro or rclpy_distro()[0]
        self._distro = found if found in DISTROS else DEFAULT_DISTRO
        self._interface_paths = tuple(interface_paths)
        self._types: Ros2Types | None = None
        self.qos_request = dds.QosRequest()
        self.warn: Callable[[str], None] = lambda text: print(f"WARNING: {text}", file=sys.stderr)
        base = node_name.strip("/")
        self._node_name = f"{base}_{os.getpid()}" if anonymous else base
        self._context: RclpyContext | None = None
        self._lock = threading.Lock()
        self._settled = False
        self.require_peers = True  # False: an empty graph lists nothing instead of failing (the daemon)
        self._long_lived = False  # the daemon's graph: settled once, then rmw keeps it current
        self._subscriptions: list[Any] = []

    @property
    def types(self) -> Ros2Types:
        """rosbags' store for the distro (made on first use: listing verbs never need it)."""
        if self._types is None:
            from rostool.interfaces.ros2_types import Ros2Types

            self._types = Ros2Types(self._distro, self._interface_paths)
        return self._types

    @property
    def context(self) -> RclpyContext:
        from rostool.graph.rclpy.context import RclpyContext

        with self._lock:
            if self._context is None:
                self._context = RclpyContext(self._node_name)
            return self._context

    @property
    def node(self) -> Any:
        return self.context.node

    @property
    def node_name(self) -> str:
        return "/" + self._node_name

    def __enter__(self) -> RclpyGraph:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def close(self) -> None:
        for sub in self._subscriptions:
            sub.close()
        self._subscriptions.clear()
        if self._context is not None:
            self._context.close()
            self._context = None

    def resolve(self, name: str) -> str:
        return resolve(name)

    def use_qos(self, qos: QosRequest) -> None:
        if qos.given:
            self.qos_request = dds.QosRequest(qos.profile, qos.reliability, qos.durability, qos.depth)

    # --- discovery ----------------------------------------------------------------------------
    def _snapshot(self) -> tuple[Any, ...]:
        node = self.node
        nodes = sorted(self._node_pairs())
        topics = sorted((n, tuple(t)) for n, t in node.get_topic_names_and_types())
        services = sorted((n, tuple(t)) for n, t in node.get_service_names_and_types())
        return nodes, topics, services

    def _node_pairs(self) -> list[tuple[str, str]]:
        own = (self._node_name, "/")
        return [p for p in self.node.get_node_names_and_namespaces() if tuple(p) != own]

    def settle(self, require_peers: bool = False, until: Callable[[], bool] | None = None) -> bool:
        """Wait until the graph stops changing (once per process) or `until()`; whether anything other
        than this process was seen."""
        if self._long_lived:
            return True
        started = time.monotonic()
        last = self._snapshot()
        baseline = {name for name, _types in last[1]}  # this node's own topics (/parameter_events)
        changed = started
        while True:
            now = time.monotonic()
            found = bool(last[0]) or bool({name for name, _types in last[1]} - baseline)
            if until is not None and until():
                return True
            # endpoints may come before their node's name (rmw learns names from ros_discovery_info), and a
            # hidden node alone (a graph daemon's, ros2cli's) is often found before the others
            named = any(not hidden_name(self._full_name(n, ns)) for n, ns in last[0])
            quiet = named and now - changed >= GRAPH_QUIET_SECONDS and now - started >= SETTLE_MIN_SECONDS
            if found and (self._settled or quiet or now - started >= SETTLE_MAX_SECONDS):
                self._settled = True
                return True
            if not found and now - started >= SETTLE_MAX_SECONDS:
                if require_peers and self.require_peers:
                    raise RostoolError(
                        f"no ROS 2 nodes found on domain {dds.domain_id()} within {SETTLE_MAX_SECONDS:g} s "
                        f"(rclpy backend): is anything running with this ROS_DOMAIN_ID? {self._range_hint()}"
                    )
                return False
            time.sleep(0.05)
            current = self._snapshot()
            if current != last:
                last, changed = current, time.monotonic()

    def wait_for_discovery(self) -> None:
        """Let discovery settle once: a long-lived graph (the daemon's) then answers at once."""
        self.settle()
        self._long_lived = True

    def wait_for_newcomers(self, limit: float = 1.0) -> None:
        """rmw folds in what discovery brings on its own threads: nothing to wait for."""

    @staticmethod
    def _range_hint() -> str:
        from rostool.graph.rclpy.facts import rclpy_range

        scope, why = rclpy_range()
        return f"Discovery range: {scope} ({why}); `rostool doctor` shows the whole set-up"

    def _full_name(self, name: str, namespace: str) -> str:
        if name == UNKNOWN_NODE or namespace.startswith("_NODE_NAMESPACE_UNKNOWN_"):
            return UNKNOWN_NODE
        return f"{namespace.rstrip('/')}/{name}"

    def _endpoints(self, topic: str) -> tuple[list[Any], list[Any]]:
        """(publishers, subscriptions) of `topic` other than this process's, as rmw describes them."""
        node, own = self.node, self._node_name
        pubs = [i for i in node.get_publishers_info_by_topic(topic) if i.node_name != own]
        subs = [i for i in node.get_subscriptions_info_by_topic(topic) if i.node_name != own]
        return pubs, subs

    # --- nodes --------------------------------------------------------------------------------
    def node_names(self) -> list[str]:
        self.settle(require_peers=True)
        return sorted(self._full_name(n, ns) for n, ns in self._node_pairs())  # a name twice: two nodes

    def node_uri(self, name: str) -> str:
        resolved = resolve(name)
        if resolved not in self.node_names():
            raise RostoolError(f"unknown node {resolved}: no ROS 2 participant announces it")
        return f"rclpy:{resolved}"

    def node_info(self, name: str) -> NodeInfo:
        resolved = resolve(name)
        self.node_uri(resolved)
        namespace, _, base = resolved.rpartition("/")
        node, ns = self.node, namespace or "/"
        try:
            pubs = node.get_publisher_names_and_types_by_node(base, ns)
            subs = node.get_subscriber_names_and_types_by_node(base, ns)
            servers = node.get_service_names_and_types_by_node(base, ns)
            clients = node.get_client_names_and_types_by_node(base, ns)
        except Exception as err:  # NodeNameNonExistentError: gone in the meantime
            raise RostoolError(f"unknown node {resolved}: {' '.join(str(err).split())}") from None

        def pairs(found: list[tuple[str, list[str]]]) -> list[tuple[str, str]]:
            return sorted({(n, t) for n, types in found for t in types})

        server_pairs = pairs(servers)
        info = NodeInfo(resolved, f"rclpy:{resolved}", None, pairs(pubs), pairs(subs),
                        sorted({n for n, _ in server_pairs}), [])  # fmt: skip
        info.service_types = dict(server_pairs)
        info.service_clients = pairs(clients)
        return info

    # --- topics -------------------------------------------------------------------------------
    def topics(self) -> list[TopicInfo]:
        self.settle(require_peers=True)
        found = []
        for name, types in sorted(self.node.get_topic_names_and_types()):
            pubs, subs = self._endpoints(name)
            if not pubs and not subs:
                continue  # only this process's own endpoints
            type_name = (pubs or subs)[0].topic_type if pubs or subs else types[0]
            info = TopicInfo(name, type_name)
            info.publishers = sorted(self._full_name(i.node_name, i.node_namespace) for i in pubs)
            info.subscribers = sorted(self._full_name(i.node_name, i.node_namespace) for i in subs)
            found.append(info)
        return found

    def topic_endpoints(self, name: str) -> list[dict[str, Any]]:
        """ros2 topic info -v's rows, from rmw's endpoint descriptions."""
        from rostool.graph.rclpy.qos import from_rclpy

        self.settle(require_peers=True)
        pubs, subs = self._endpoints(resolve(name))
        rows = []
        for kind, infos in (("PUBLISHER", pubs), ("SUBSCRIPTION", subs)):
            for i in infos:
                rows.append({
                    "node": self._full_name(i.node_name, i.node_namespace), "endpoint_type": kind,
                    "type": i.topic_type, "type_hash": _type_hash(i), "gid": bytes(i.endpoint_gid).hex("."),
                    "qos": vars(from_rclpy(i.qos_profile)).copy(),
                })  # fmt: skip
        return sorted(rows, key=lambda r: (r["endpoint_type"] != "PUBLISHER", r["node"]))

    def topic_type(self, name: str) -> str | None:
        resolved = resolve(name)

        def published() -> bool:
            return bool(self._endpoints(resolved)[0])

        deadline = time.monotonic() + TOPIC_WAIT_SECONDS
        self.settle(until=published)
        while not published() and time.monotonic() < deadline:
            time.sleep(0.05)
        pubs, subs = self._endpoints(resolved)
        return (pubs or subs)[0].topic_type if pubs or subs else None

    def subscribe(
        self,
        topic: str,
        on_message: Callable[[Received], None],
        on_error: Callable[[str], None] | None = None,
    ) -> Subscription:
        from rostool.graph.rclpy.subscription import RclpySubscription

        _ = self.context  # started here, not in the subscription's thread
        sub = RclpySubscription(self, resolve(topic), on_message, on_error or self.warn)
        self._subscriptions.append(sub)
        return sub

    def publisher(self, topic: str, type_name: str, latch: bool = False) -> RclpyPublisher:
        from rostool.graph.rclpy.qos import to_rclpy

        resolved = resolve(topic)
        store_name = self.store_name(type_name)
        cls = rtypes.python_class(store_name)
        existing = self.topic_type(resolved)
        if existing and existing != store_name:
            raise RostoolError(
                f"topic {resolved} already has type {existing}; cannot publish {store_name} on it"
            )
        request = self.qos_request
        base = request.base()
        if latch and request.durability is None:
            base = dds.QosProfile(base.reliability, "transient_local", base.depth)
        writer = self.node.create_publisher(cls, resolved, to_rclpy(request.apply(base)))
        return RclpyPublisher(resolved, store_name, writer, self.types)

    def store_name(self, type_name: str) -> str:
        """`pkg/Type` or `pkg/msg/Type` -> `pkg/msg/Type`, known to rosbags' store (from the class rclpy
        imports when neither the store nor a source file has it)."""
        from rostool.interfaces.names import to_store_name

        store_name = to_store_name(type_name.strip())
        if not self.types.knows(store_name):
            rtypes.ensure_known(self.types, store_name)
        return store_name

    def message_class(self, type_name: str) -> type:
        return self.types.store.types[self.store_name(type_name)]  # type: ignore[no-any-return]

    def build_message(self, type_name: str, value: Any) -> Any:
        from rostool.interfaces.fill import build_message

        store_name = self.store_name(type_name)
        return build_message(self.types.store, store_name, self.types.with_defaults(store_name, value))


def _type_hash(info: Any) -> str | None:
    text = str(getattr(info, "topic_type_hash", "") or "")
    return text if text.startswith("RIHS01_") and text[7:].strip("0") else None


class RclpyPublisher:
    def __init__(self, topic: str, store_name: str, writer: Any, types: Ros2Types) -> None:
        self.topic = topic
        self.type_name = store_name
        self._writer = writer
        self._types = types

    def publish(self, message: object) -> None:
        self.publish_raw(self._types.serialize(message, self.type_name))

    def publish_raw(self, payload: bytes) -> None:
        """CDR bytes with their encapsulation header, as rmw publishes serialized messages."""
        self._writer.publish(bytes(payload))

    def wait_for_subscribers(self, count: int, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while self.subscriber_count < count:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    @property
    def subscriber_count(self) -> int:
        return int(self._writer.get_subscription_count())
