"""Where `bag record` gets messages: a ROS 1 graph (TCPROS bytes) or a ROS 2 graph (CDR bytes over DDS).

A source finds published topics, subscribes with a callback `put(topic, payload, origin)` called from
network threads, and describes an origin once (the connection header a bag stores). `origin` is whatever
identifies one publisher connection cheaply: a TCPROS link in ROS 1, the topic's type name in ROS 2.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any, Literal, Protocol

from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.bag.crossver import CrossVersionStores
    from rostool.graph.base import Received
    from rostool.graph.ros1.graph import Ros1Graph
    from rostool.graph.ros2.graph import Ros2Graph

Encoding = Literal["ros1", "cdr"]
Put = Callable[[str, bytes, Any], None]


class RecordSource(Protocol):
    encoding: Encoding
    types: Any  # ROS 1: the graph's TypeRegistry
    store: Any  # ROS 2: the graph's rosbags type store

    def resolve(self, name: str) -> str: ...

    def published_topics(self) -> list[str]: ...

    def subscribed_topics(self, node: str) -> list[str]: ...

    def subscribe(self, topic: str, put: Put) -> None: ...

    def describe(self, topic: str, origin: Any) -> dict[str, str]: ...

    def close(self) -> None: ...


class Ros1Source:
    """Raw TCPROS subscriptions (md5 `*`): bytes are stored with the publisher's own connection header."""

    encoding: Encoding = "ros1"

    def __init__(self, graph: Ros1Graph) -> None:
        self.graph = graph
        self.types = graph.types
        self.store = None

    def resolve(self, name: str) -> str:
        from rostool.graph.ros1.names import resolve

        return resolve(name)

    def published_topics(self) -> list[str]:
        try:
            return list(self.graph.master.published_topics())
        except RostoolError:
            return []  # the master is away: keep recording what is subscribed (as rosbag does)

    def subscribed_topics(self, node: str) -> list[str]:
        return _subscribed_by(self.graph, node)

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


class Ros2Source:
    """DDS readers that adapt to the publishers' QoS (or use --qos-*); samples stay CDR bytes."""

    encoding: Encoding = "cdr"

    def __init__(self, graph: Ros2Graph, warn: Callable[[str], None], include_hidden: bool = False) -> None:
        self.graph = graph
        self.include_hidden = include_hidden
        self.types = graph.types
        self.store = graph.types.store
        self.warn = warn
        graph.warn = warn  # the subscriptions' warnings (incompatible QoS) go to the same place

    def resolve(self, name: str) -> str:
        return self.graph.resolve(name)

    def published_topics(self) -> list[str]:
        """Topics with a publisher; hidden ones (a name part starting with `_`) are left out unless asked
        for, as `ros2 bag record -a` does."""
        cache = self.graph.session.cache
        cache.poll()
        writers = [e.ros for e in cache.remote_endpoints() if e.is_writer]
        published = {ros[1] for ros in writers if ros is not None and ros[0] == "topic"}
        return sorted(t for t in published if self.include_hidden or not _hidden(t))

    def subscribed_topics(self, node: str) -> list[str]:
        return _subscribed_by(self.graph, node)

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


def _subscribed_by(graph: Ros1Graph | Ros2Graph, node: str) -> list[str]:
    """The topics `node` subscribes to now; none while the graph does not answer."""
    try:
        return [t.name for t in graph.topics() if node in t.subscribers]
    except RostoolError:
        return []


def _hidden(name: str) -> bool:
    return any(part.startswith("_") for part in name.split("/"))


def ros1_header_for_cdr(
    fields: dict[str, str], src_store: Any, stores: CrossVersionStores
) -> tuple[dict[str, str], Callable[[bytes], Any]]:
    """A ROS 1 connection header (type, md5sum, definition) and byte converter for a ROS 2 type."""
    msgtype = fields["type"]
    if "/msg/" not in msgtype:
        raise RostoolError(f"type {msgtype} has no ROS 1 equivalent")
    dst = stores.store_for(src_store, msgtype, msgtype)
    text, md5 = dst.generate_msgdef(msgtype, ros_version=1)
    header = {
        "topic": fields["topic"],
        "type": msgtype.replace("/msg/", "/"),
        "md5sum": md5,
        "message_definition": text,
        "callerid": fields["callerid"],
        "latching": fields["latching"],
    }
    return header, partial(src_store.cdr_to_ros1, typename=msgtype)
