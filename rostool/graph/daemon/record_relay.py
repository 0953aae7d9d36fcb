"""`bag record`'s source while a graph daemon serves: each topic's messages come through a relay (a reader
in the daemon's graph, which already knows the topic's publishers), so a recording starts at once instead
of after this process's own participant has been discovered and matched (a second or more with Fast DDS
peers, more under load). What a stream of messages does not carry comes from the daemon too: the topics
published now (-a, --regex, --node: asked again every poll, answered from its settled graph), and each
topic's publishers' QoS for the bag's metadata (`topic_endpoints`, as `topic info -v`). A relay's READY
frame says when its reader has matched, and `wait_ready` holds --duration's clock on it as the direct
source does on its own readers.

Static topics (a type given up front, before any publisher shows it) are subscribed directly: a relay is
made for a topic the daemon can describe. A relay the daemon cannot make (too many, a type it cannot
learn) or that ends mid-recording subscribes directly too (relay_client.py; the latter says so).
"""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Any, Protocol

from rostool.errors import RostoolError
from rostool.graph.recording import Encoding, Put, subscribed_by
from rostool.graph.ros2_base.recording import START_WAIT_SECONDS
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from collections.abc import Callable

    from rostool.graph.base import OnError, OnMessage, Received, Subscription, TopicEndpoint, TopicInfo
    from rostool.graph.ros2_base.recording import Ros2Source

READY_POLL = 0.005


class RelayingGraph(Protocol):
    """What the relayed source asks of the graph it records from (a DaemonGraph)."""

    types: Any
    direct: Any  # the direct graph, made on first use (static topics)

    def resolve(self, name: str) -> str: ...

    def topics(self) -> list[TopicInfo]: ...

    def topic_endpoints(self, name: str) -> list[TopicEndpoint]: ...

    def relayed_subscription(
        self, topic: str, on_message: OnMessage, on_error: OnError, warn: Callable[[str], None]
    ) -> Subscription: ...


class RelayedRecordSource:
    encoding: Encoding = "cdr"

    def __init__(self, graph: RelayingGraph, warn: Callable[[str], None], include_hidden: bool) -> None:
        self.graph = graph
        self.warn = warn
        self.include_hidden = include_hidden
        # the types relayed messages are decoded and described with: the daemon's distro, shared with a
        # direct graph made later (lent_types.py), so the bag's definitions are those the relays learned
        self.types = graph.types
        self.store = self.types.store
        self.resolve = graph.resolve
        self._subscriptions: list[Subscription] = []
        self._direct: Ros2Source | None = None  # the static topics' source, made on first need
        self._direct_lock = threading.Lock()

    # --- which topics ---------------------------------------------------------------------------------
    def published_topics(self) -> list[str]:
        """Topics another node publishes now, as the daemon's graph shows them (hidden ones only when asked
        for, as `ros2 bag record -a`)."""
        try:
            topics = self.graph.topics()
        except RostoolError:  # nobody publishes anything
            return []
        shown = self.include_hidden
        return sorted(t.name for t in topics if t.publishers and (shown or not hidden_name(t.name)))

    def topics_present(self) -> list[str]:
        """The topics published at start-up (--no-discovery's fixed list): the daemon's graph is settled."""
        return self.published_topics()

    def subscribed_topics(self, node: str) -> list[str]:
        return subscribed_by(self.graph, node)

    # --- subscribing ----------------------------------------------------------------------------------
    def known_type(self, type_name: str) -> str:
        return self._direct_source().known_type(type_name)

    def subscribe(self, topic: str, put: Put, type_name: str | None = None) -> None:
        if type_name is not None:  # no relay can be made before a publisher shows the topic
            self._direct_source().subscribe(topic, put, type_name)
            return

        def on_message(received: Received) -> None:
            put(topic, received.payload, received.type_name)

        subscription = self.graph.relayed_subscription(
            topic, on_message, lambda text: self.warn(f"{topic}: {text}"), self.warn
        )
        self._subscriptions.append(subscription)

    def wait_ready(self, timeout: float = START_WAIT_SECONDS, stop: threading.Event | None = None) -> None:
        """Return once every relay said READY (its reader matched the publishers the daemon knew, or it
        knew none) and the direct subscriptions, if any, record: --duration counts from then. At most
        `timeout` s; at once when `stop` is set (Ctrl+C)."""
        stop = stop or threading.Event()
        deadline = time.monotonic() + timeout
        direct = self._direct
        if direct is not None:
            direct.wait_ready(timeout, stop)
        while time.monotonic() < deadline and not all(_ready(s) for s in self._subscriptions):
            if stop.wait(READY_POLL):
                return

    def describe(self, topic: str, origin: Any) -> dict[str, str]:
        """The bag's view of the topic: its ROS 2 type, and whether its publishers latch or are best effort
        (the QoS the daemon's discovery holds for them)."""
        direct = self._direct
        if direct is not None and topic in direct._static:
            return direct.describe(topic, origin)
        try:
            writers = [e for e in self.graph.topic_endpoints(topic) if e["endpoint_type"] == "PUBLISHER"]
        except RostoolError:  # the publisher went: nothing says it latched
            writers = []
        latching = any(w["qos"]["durability"] == "transient_local" for w in writers)
        best_effort = bool(writers) and all(w["qos"]["reliability"] == "best_effort" for w in writers)
        return {"topic": topic, "type": str(origin), "callerid": "", "latching": "1" if latching else "0",
                "reliability": "best_effort" if best_effort else "reliable"}  # fmt: skip

    def close(self) -> None:
        subscriptions, self._subscriptions = self._subscriptions, []
        for subscription in subscriptions:
            subscription.close()
        if self._direct is not None:
            self._direct.close()

    def _direct_source(self) -> Ros2Source:
        with self._direct_lock:
            if self._direct is None:
                self._direct = self.graph.direct.record_source(self.warn, self.include_hidden)  # type: ignore[attr-defined]
            return self._direct


def _ready(subscription: Subscription) -> bool:
    """A relay: it said READY (or its first message came, or it went direct); a direct subscription (the
    daemon could not relay it): its reader matched what discovery knew."""
    ready = getattr(subscription, "ready", None)
    if isinstance(ready, threading.Event):
        return ready.is_set()
    wait_matched = getattr(subscription, "wait_matched", None)
    return True if wait_matched is None else bool(wait_matched(0.0))
