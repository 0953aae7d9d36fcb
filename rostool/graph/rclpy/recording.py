"""`bag play` and `bag record` on the rclpy backend: bytes in and out, as the DDS backend moves them.

Play publishes each message's CDR bytes through an rclpy publisher of the type rclpy imports; record takes
raw (serialized) subscriptions that adapt to the publishers' QoS (subscription.py), and the bag stores the
bytes as they came.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostool.graph.recording import Encoding, Put, subscribed_by
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.base import Received
    from rostool.graph.rclpy.graph import RclpyGraph, RclpyPublisher


class BagVerbs:
    def raw_publisher(self: RclpyGraph, topic: str, wire_type: Any, latch: bool = False) -> RclpyPublisher:
        return self.publisher(topic, str(wire_type), latch)

    def record_source(
        self: RclpyGraph, warn: Callable[[str], None], include_hidden: bool = False
    ) -> RclpySource:
        return RclpySource(self, warn, include_hidden)


class RclpySource:
    """`bag record`'s source on rclpy: the topics rmw knows a publisher of, raw subscriptions to them."""

    encoding: Encoding = "cdr"

    def __init__(self, graph: RclpyGraph, warn: Callable[[str], None], include_hidden: bool = False) -> None:
        self.graph = graph
        self.include_hidden = include_hidden
        self.types = graph.types
        self.store = graph.types.store
        self.warn = warn
        self.resolve = graph.resolve
        graph.warn = warn  # the subscriptions' warnings (incompatible QoS) go to the same place
        self._settled = False

    def published_topics(self) -> list[str]:
        """Topics another node publishes; hidden ones only when asked for, as `ros2 bag record -a` does."""
        graph = self.graph
        if not self._settled:  # once: later polls (-a, topics that appear later) must not wait
            graph.settle()
            self._settled = True
        names = [name for name, _types in graph.node.get_topic_names_and_types()]
        published = [name for name in names if graph._endpoints(name)[0]]
        return sorted(t for t in published if self.include_hidden or not hidden_name(t))

    def subscribed_topics(self, node: str) -> list[str]:
        return subscribed_by(self.graph, node)

    def subscribe(self, topic: str, put: Put) -> None:
        def on_message(received: Received) -> None:
            put(topic, received.payload, received.type_name)

        self.graph.subscribe(topic, on_message, lambda text: self.warn(f"{topic}: {text}"))

    def describe(self, topic: str, origin: Any) -> dict[str, str]:
        """The bag's view of the topic: its ROS 2 type and whether its publishers latch."""
        from rclpy.qos import DurabilityPolicy

        pubs, _subs = self.graph._endpoints(topic)
        latching = any(p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in pubs)
        return {"topic": topic, "type": str(origin), "callerid": "", "latching": "1" if latching else "0"}

    def close(self) -> None:
        self.graph.close()
