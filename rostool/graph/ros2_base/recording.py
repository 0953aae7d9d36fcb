"""`bag record`'s source on ROS 2: subscriptions that adapt to the publishers' QoS (or use --qos-*), over
either transport; samples stay CDR bytes."""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.recording import Encoding, Put, subscribed_by
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.base import Received, Subscription
    from rostool.graph.ros2_base.transport import EndpointView, Ros2Host


# how long a recording's first subscriptions wait for their publishers to be discovered and matched: a fresh
# participant meets Fast DDS's endpoints on its 1 s heartbeat, a Fast DDS one on the peer's 3 s announcement
START_WAIT_SECONDS = 3.0
READY_GRACE = 0.3  # after one subscription matched, how long one without a known publisher is waited for
# a static topic's first message came from a publisher discovery may not have folded in yet: how long the
# bag's description of the topic (its QoS) waits for it to show
STATIC_DESCRIBE_WAIT = 1.0


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
        self._subscriptions: list[Subscription] = []
        self._static: dict[str, str] = {}  # topics subscribed with a type given up front: their types
        self._offers: dict[str, list[EndpointView]] = {}  # and their publishers last seen

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
        """Topics published at start-up, once discovery settled as for a listing (--no-discovery's fixed
        list)."""
        with contextlib.suppress(RostoolError):  # nothing answers: nothing is present
            self.graph._listing()
        return self._visible(self.graph.published_topics())

    def _visible(self, topics: set[str]) -> list[str]:
        return sorted(t for t in topics if self.include_hidden or not hidden_name(t))

    def subscribed_topics(self, node: str) -> list[str]:
        return subscribed_by(self.graph, node)

    def known_type(self, type_name: str) -> str:
        """The store name of a type given up front (--static-topics-path); one line when the type store
        cannot describe it."""
        return self.graph.store_name(type_name)

    def subscribe(self, topic: str, put: Put, type_name: str | None = None) -> None:
        first = type_name is not None  # a static topic: note its publishers as its first message comes
        if type_name is not None:
            self._static[topic] = type_name

        def on_message(received: Received) -> None:
            nonlocal first
            if first:
                first = False
                self._note_offers(topic)
            put(topic, received.payload, received.type_name)

        subscription = self.graph.subscribe(
            topic, on_message, lambda text: self.warn(f"{topic}: {text}"), type_name=type_name
        )
        self._subscriptions.append(subscription)

    def _note_offers(self, topic: str, wait: float = 0.0) -> list[EndpointView]:
        """A static topic's publishers as discovery knows them now (waiting at most `wait` s for one), else
        the last ones seen: a publisher that came and went still describes what it sent."""
        deadline, type_name = time.monotonic() + wait, self._static[topic]
        while True:
            writers = [e for e in self.graph.topic_views(topic) if e.is_writer and e.type_name == type_name]
            if writers or time.monotonic() >= deadline:
                break
            time.sleep(0.01)
        if writers:
            self._offers[topic] = writers
        return writers or self._offers.get(topic, [])

    def wait_ready(self, timeout: float = START_WAIT_SECONDS, stop: threading.Event | None = None) -> None:
        """Return once the subscriptions made so far record: each has matched the publishers discovery
        knew when its reader was made (the transport's matched count). A topic whose publisher is not
        known yet is waited for only READY_GRACE s after another one matched (discovery brings a peer's
        endpoints together: it is unpublished, or its publisher is still far), and `timeout` s at most.
        The recorder calls this before it starts --duration's clock, so 3 s of recording are 3 s of
        messages, not a discovery and the rest. Ends at once when `stop` is set (Ctrl+C)."""
        stop = stop or threading.Event()
        deadline = time.monotonic() + timeout
        grace_ends: float | None = None
        while (now := time.monotonic()) < deadline:
            waiting = [s for s in self._subscriptions if not _matched(s)]
            if not waiting:
                return
            if grace_ends is None and len(waiting) < len(self._subscriptions):
                grace_ends = now + READY_GRACE
            if grace_ends is not None and now >= grace_ends and not any(_has_publishers(s) for s in waiting):
                return
            if stop.wait(0.005):
                return

    def describe(self, topic: str, origin: Any) -> dict[str, str]:
        """The bag's view of the topic: its ROS 2 type and whether its publishers latch."""
        if topic in self._static:  # subscribed before any publisher was known
            writers = self._note_offers(topic, STATIC_DESCRIBE_WAIT)
        else:
            writers = [e for e in self.graph.topic_views(topic) if e.is_writer]
        latching = any(e.qos.durability == "transient_local" for e in writers)
        best_effort = bool(writers) and all(e.qos.reliability == "best_effort" for e in writers)
        return {"topic": topic, "type": str(origin), "callerid": "", "latching": "1" if latching else "0",
                "reliability": "best_effort" if best_effort else "reliable"}  # fmt: skip

    def close(self) -> None:
        self.graph.close()


def _matched(subscription: Subscription) -> bool:
    wait_matched = getattr(subscription, "wait_matched", None)
    return True if wait_matched is None else bool(wait_matched(0.0))


def _has_publishers(subscription: Subscription) -> bool:
    return bool(getattr(subscription, "publishers_known", True))
