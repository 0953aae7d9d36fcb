"""`bag record`'s source on ROS 2: subscriptions that adapt to the publishers' QoS (or use --qos-*), over
either transport; samples stay CDR bytes."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostool.graph.recording import Encoding, Put, subscribed_by
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.base import Received
    from rostool.graph.ros2_base.transport import Ros2Host


class Ros2Source:
    encoding: Encoding = "cdr"

    def __init__(self, graph: Ros2Host, warn: Callable[[str], None], include_hidden: bool = False) -> None:
        self.graph = graph
        self.include_hidden = include_hidden
        self.types = graph.types
        self.store = graph.types.store
        self.warn = warn
        self.resolve = graph.resolve
        graph.warn = warn  # the subscriptions' warnings (incompatible QoS) go to the same place

    def published_topics(self) -> list[str]:
        """Topics another node publishes now, as discovery knows them this moment: the recorder asks again
        every poll, so a topic is subscribed the moment its publisher is known, never after a settling
        window; hidden ones (a name part starting with `_`) are left out unless asked for, as `ros2 bag
        record -a` does."""
        graph = self.graph
        graph.wait_for_newcomers(0.0)  # folds in what discovery brought, waiting for nothing
        published = {topic for topic, view in graph._all_topic_views() if view.is_writer}
        return self._visible(published)

    def topics_present(self) -> list[str]:
        """Topics published at start-up, once discovery settled (--no-discovery's fixed list)."""
        return self._visible(self.graph.published_topics())

    def _visible(self, topics: set[str]) -> list[str]:
        return sorted(t for t in topics if self.include_hidden or not hidden_name(t))

    def subscribed_topics(self, node: str) -> list[str]:
        return subscribed_by(self.graph, node)

    def subscribe(self, topic: str, put: Put) -> None:
        def on_message(received: Received) -> None:
            put(topic, received.payload, received.type_name)

        self.graph.subscribe(topic, on_message, lambda text: self.warn(f"{topic}: {text}"))

    def describe(self, topic: str, origin: Any) -> dict[str, str]:
        """The bag's view of the topic: its ROS 2 type and whether its publishers latch."""
        writers = [e for e in self.graph.topic_views(topic) if e.is_writer]
        latching = any(e.qos.durability == "transient_local" for e in writers)
        best_effort = bool(writers) and all(e.qos.reliability == "best_effort" for e in writers)
        return {"topic": topic, "type": str(origin), "callerid": "", "latching": "1" if latching else "0",
                "reliability": "best_effort" if best_effort else "reliable"}  # fmt: skip

    def close(self) -> None:
        self.graph.close()
