"""Nodes and topics of a ROS 1 graph: the master answers what it knows, a native node (registered on first
need) subscribes and publishes. `graph.Ros1Graph` adds services, actions, parameters and bags on top."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from rostool.errors import RostoolError
from rostool.graph.base import (
    Connection,
    NodeInfo,
    OnError,
    OnMessage,
    Publisher,
    Received,
    Subscription,
    TopicInfo,
)
from rostool.graph.ros1 import env
from rostool.graph.ros1.master_client import MasterClient, RemoteError, Unreachable, call
from rostool.graph.ros1.names import anonymous, resolve
from rostool.graph.ros1.node import Node
from rostool.graph.ros1.topics import InboundLink
from rostool.interfaces.ros1 import Ros1Type, TypeRegistry
from rostool.interfaces.sources import Interfaces, interfaces

C = TypeVar("C", bound="Ros1Core")


class Ros1Core:
    """Read-only verbs use the master alone; subscribing or publishing starts a node lazily."""

    def __init__(self, node_name: str = "rostool", interface_paths: Sequence[str] = ()) -> None:
        self.interface_paths = tuple(interface_paths)
        self._node_name = node_name
        self._node: Node | None = None
        self.types = TypeRegistry()
        self.master = MasterClient(env.master_uri(), anonymous(node_name))

    @property
    def node(self) -> Node:
        if self._node is None:
            self.master.get_pid()  # one clear "cannot reach the master" error before binding anything
            self._node = Node(self._node_name, anonymous=True)
        return self._node

    def __enter__(self: C) -> C:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._node is not None:
            self._node.close()
            self._node = None

    def resolve(self, name: str) -> str:
        return resolve(name)

    # --- nodes --------------------------------------------------------------------------------
    def node_names(self) -> list[str]:
        publishers, subscribers, services = self.master.system_state()
        names = {n for group in (publishers, subscribers, services) for _name, nodes in group for n in nodes}
        return sorted(names)

    def node_uri(self, name: str) -> str:
        name = resolve(name)
        try:
            return self.master.lookup_node(name)
        except RemoteError as err:
            raise RostoolError(f"unknown node {name}: it is not registered with the master") from err

    def node_info(self, name: str) -> NodeInfo:
        name = resolve(name)
        uri = self.node_uri(name)
        publishers, subscribers, services = self.master.system_state()
        types = self.master.topic_types()
        pubs = [(t, types.get(t, "?")) for t, nodes in publishers if name in nodes]
        subs = [(t, types.get(t, "?")) for t, nodes in subscribers if name in nodes]
        srvs = sorted(s for s, nodes in services if name in nodes)
        pid: int | None = None
        connections: list[Connection] = []
        try:
            pid = int(call(uri, "getPid", self.master.caller_id, what=f"node {name}", timeout=3))
            bus = call(uri, "getBusInfo", self.master.caller_id, what=f"node {name}", timeout=3)
            for entry in bus:
                _cid, peer, direction, transport, topic = entry[:5]
                if len(entry) > 5 and not entry[5]:
                    continue  # not connected (yet): rosnode leaves these out too
                connections.append(
                    Connection(topic, peer, "outbound" if direction == "o" else "inbound", transport)
                )
        except (Unreachable, RemoteError):
            pid = None
        return NodeInfo(name, uri, pid, sorted(pubs), sorted(subs), srvs, connections)

    def ping(self, name: str) -> float:
        uri = self.node_uri(name)
        start = time.perf_counter()
        try:
            call(uri, "getPid", self.master.caller_id, what=f"node {resolve(name)}", timeout=3)
        except Unreachable as err:
            raise RostoolError(f"node {resolve(name)} does not answer at {uri}: {err}") from err
        return (time.perf_counter() - start) * 1000.0

    def kill(self, name: str) -> None:
        uri = self.node_uri(name)
        # A node often closes its server while answering; like rosnode, that counts as killed.
        with contextlib.suppress(Unreachable, RemoteError):
            call(uri, "shutdown", self.master.caller_id, "user request", what=f"node {name}", timeout=3)

    # --- topics -------------------------------------------------------------------------------
    def topics(self) -> list[TopicInfo]:
        publishers, subscribers, _services = self.master.system_state()
        types = self.master.topic_types()
        found: dict[str, TopicInfo] = {}
        for topic, nodes in publishers:
            found.setdefault(topic, TopicInfo(topic, types.get(topic, "?"))).publishers.extend(sorted(nodes))
        for topic, nodes in subscribers:
            found.setdefault(topic, TopicInfo(topic, types.get(topic, "?"))).subscribers.extend(sorted(nodes))
        return [found[name] for name in sorted(found)]

    def topic_type(self, name: str) -> str | None:
        return self.master.topic_types().get(resolve(name))

    def subscribe(self, topic: str, on_message: OnMessage, on_error: OnError | None = None) -> Subscription:
        resolved = resolve(topic)
        registry = self.types
        decoders: dict[int, Callable[[bytes], Any]] = {}

        def decoder_for(link: InboundLink) -> Callable[[bytes], Any]:
            header = link.header

            def decode(payload: bytes) -> Any:
                msg_type = registry.from_header(header)
                decoders[link.id] = msg_type.deserialize
                return msg_type.deserialize(payload)

            return decode

        clock = time.time_ns

        def deliver(payload: bytes, link: InboundLink) -> None:
            decoder = decoders.get(link.id) or decoders.setdefault(link.id, decoder_for(link))
            on_message(Received(resolved, payload, clock(), link.header.get("type", "*"), decoder))

        return self.node.subscribe(resolved, deliver, on_error=on_error)

    def publisher(self, topic: str, type_name: str, latch: bool = False) -> Publisher:
        resolved = resolve(topic)
        msg_type = self.wire_type(type_name)
        existing = self.topic_type(resolved)
        if existing and existing not in (msg_type.name, "*"):
            raise RostoolError(
                f"topic {resolved} already has type {existing}; cannot publish {msg_type.name} on it"
            )
        return self.node.advertise(resolved, msg_type, latch)

    def catalog(self) -> Interfaces:
        """The .msg/.srv/.action sources of `interface_paths` (then the built-in store)."""
        return interfaces(self.interface_paths)

    def wire_type(self, type_name: str) -> Ros1Type:
        """A type to publish: from .msg files in the source trees first, then the built-in store."""
        return self.catalog().message(type_name)

    def message_class(self, type_name: str) -> type:
        return self.wire_type(type_name).message_class()

    def build_message(self, type_name: str, value: Any) -> Any:
        from rostool.interfaces.fill import build_message

        msg_type = self.wire_type(type_name)
        return build_message(msg_type.store, msg_type.store_name, value)
