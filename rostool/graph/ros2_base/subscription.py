"""A ROS 2 subscription that drains in its own thread: it waits for the topic's publishers, subscribes with
the QoS adapted to them (as ros2 topic echo does), and hands on CDR bytes as `Received`. Given the type up
front (`bag record --static-topics-path`), it subscribes at once with the QoS adapted to whatever publishers
are known then (none: the request's own, reliable and volatile by default), as rosbag2 does.

When a publisher appears that the reader cannot match and the QoS was left to rostool, it subscribes again
with the QoS adapted to every publisher now known; otherwise it warns, or fails when no publisher can serve
it. How it reads (a DDS wait set, an rclpy raw subscription) is the transport's `_read_with`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.base import OnError, OnMessage, Received
from rostool.graph.ros2_base.qos import adapt_to_publishers, serves

if TYPE_CHECKING:
    from rostool.graph.ros2_base.qos import QosProfile, QosRequest
    from rostool.graph.ros2_base.transport import EndpointView, Ros2Host

READER_CACHE_DEPTH = 1000  # a deep local history lets a busy moment pass without losing samples
SUBSCRIBERS_ONLY_WAIT = 0.5  # a topic with subscribers only: how long publishers are given to appear
# how often the transport's view is asked for the topic's publishers: the reader is made this long at most
# after discovery knew one (a look at what discovery already holds costs microseconds)
DISCOVERY_POLL = 0.01
MATCH_POLL = 0.005  # how often wait_matched looks at the reader's matched count (a status read)
REJOIN_POLL = 0.02  # how often a reader that may be made again (`_rejoins`) looks for its first publisher


class DrainingSubscription:
    thread_name = "ros2 sub"

    def __init__(
        self, graph: Ros2Host, topic: str, on_message: OnMessage, on_error: OnError,
        request: QosRequest | None = None, warn: Callable[[str], None] | None = None,
        type_name: str | None = None,
    ) -> None:  # fmt: skip
        self._graph = graph
        self._static_type = type_name  # a store name the caller resolved: no publisher is waited for
        self._rejoined = False
        self._other_types: set[str] = set()  # a static topic's publishers of another type, warned about
        self._topic = topic
        self._on_message = on_message
        self._on_error = on_error
        self._closed = threading.Event()
        self._expected: int | None = None  # the publishers discovery knew when the reader was made
        # the QoS request and the warnings' place: the graph's, unless given (a graph daemon's subscriptions
        # each serve a client of its own: ros2_base/relaying.py)
        self._request = graph.qos_request if request is None else request
        self._warn = graph.warn if warn is None else warn
        self._setup()
        self._since = self._discovery_started()
        self._thread = threading.Thread(target=self._run, name=f"{self.thread_name} {topic}", daemon=True)
        self._thread.start()

    # --- the transport's -------------------------------------------------------------------------------
    def _setup(self) -> None:
        """The transport's own state, made before the thread starts."""

    def _discovery_started(self) -> float:
        """Since when (monotonic) discovery has been looking: a topic with subscribers only is given
        SUBSCRIBERS_ONLY_WAIT from then for a publisher to show up."""
        return time.monotonic()

    def _known_type(self, type_name: str, writers: list[EndpointView]) -> str:
        """The store name of the topic's type, made known to rosbags' store (from its publishers)."""
        raise NotImplementedError

    def _read_with(self, store_name: str, profile: QosProfile) -> QosProfile | None:
        """Read until closed, or until a publisher this reader cannot match calls for another QoS
        (returned)."""
        raise NotImplementedError

    def _wake(self) -> None:
        """Make a reading `_read_with` notice that the subscription is closing."""

    def _drop(self) -> None:
        """Delete the transport's reader."""

    def _matched_count(self) -> int | None:
        """How many publishers the transport's reader has matched; None while there is no reader."""
        return None

    # --- shared ----------------------------------------------------------------------------------------
    @property
    def publishers_known(self) -> bool:
        """Whether discovery showed the topic's publishers (the reader is made, or about to be)."""
        return self._expected is not None

    def wait_matched(self, timeout: float) -> bool:
        """Wait for the event a recording starts on: the reader exists and has matched every publisher
        discovery knew when it was made (its matched count), at most `timeout` s. False when no publisher
        was known in that time, or one never matched (incompatible QoS: warned about), or closed."""
        deadline = time.monotonic() + timeout
        while not self._closed.is_set():
            expected, count = self._expected, self._matched_count()
            if expected is not None and count is not None and count >= expected:
                return True
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            self._closed.wait(min(MATCH_POLL, left))
        return False

    def close(self) -> None:
        self._closed.set()
        self._wake()
        if threading.current_thread() is not self._thread:
            self._thread.join(2.0)
        self._drop()

    def _run(self) -> None:
        try:
            chosen = self._wait_for_type()
            if chosen is None:
                return
            store_name, profile = chosen
            next_profile: QosProfile | None = profile
            while next_profile is not None and not self._closed.is_set():
                next_profile = self._read_with(store_name, next_profile)
        except RostoolError as err:
            self._on_error(str(err))

    def _endpoints(self) -> list[EndpointView]:
        return self._graph.topic_views(self._topic)

    def _wait_for_type(self) -> tuple[str, QosProfile] | None:
        if self._static_type is not None:
            return self._static_start(self._static_type)
        while not self._closed.is_set():
            endpoints = self._endpoints()
            writers = [e for e in endpoints if e.is_writer]
            known = writers or endpoints
            if known and (writers or time.monotonic() - self._since >= SUBSCRIBERS_ONLY_WAIT):
                store_name = self._known_type(known[0].type_name, writers)
                profile, notes = adapt_to_publishers(self._request, [w.qos for w in writers])
                for note in notes:
                    self._warn(note)
                self._expected = len(writers)
                return store_name, profile
            self._closed.wait(DISCOVERY_POLL)
        return None

    def _static_start(self, store_name: str) -> tuple[str, QosProfile]:
        """The reader of a type given up front, made now: adapted to the publishers of that type known now;
        publishers of another type never match it (said once)."""
        writers = [e for e in self._endpoints() if e.is_writer]
        self._warn_other_types(writers)
        same = [w for w in writers if w.type_name == store_name]
        profile, notes = adapt_to_publishers(self._request, [w.qos for w in same])
        for note in notes:
            self._warn(note)
        self._expected = len(same)
        return store_name, profile

    def _rejoins(self) -> bool:
        """Whether the transport makes the reader again once its first publisher is known (discovery shows
        it, or the reader matched it), before any message came: a reader made before any publisher was
        known (a static topic's). The DDS transport does (measured with Fast DDS publishers): a new Fast
        DDS participant learns of a Cyclone reader that was there before it only on a discovery heartbeat,
        about 1 s later, but of one made after it at once; and a Fast DDS writer that did match the early
        reader first sends before Cyclone knows the writer, whose reader then takes nothing until the
        writer's next heartbeat. A reader made once the writer is known is matched and in step at once.
        The rclpy transport does not: a Fast DDS reader catches up with a writer that matched it first,
        and making it again then lost the messages it was catching up on. Once."""
        return self._static_type is not None and self._expected == 0 and not self._rejoined

    def _static_writer_known(self) -> bool:
        """A publisher of the static type is known to discovery now (one of another type is warned about)."""
        writers = [e for e in self._endpoints() if e.is_writer]
        self._warn_other_types(writers)
        return any(w.type_name == self._static_type for w in writers)

    def _warn_other_types(self, writers: list[EndpointView]) -> None:
        """Publishers of another type than the static one never match its reader: said once per type."""
        others = sorted({w.type_name for w in writers} - {self._static_type, *self._other_types})
        if others:
            self._other_types.update(others)
            self._warn(
                f"{self._topic} is published as {', '.join(others)}, not {self._static_type}: those "
                "publishers' messages are not recorded"
            )

    def _cache_profile(self, profile: QosProfile) -> QosProfile:
        """A reader's depth is local (it never affects matching): a deep cache lets a busy moment pass
        without losing samples a reliable publisher already delivered."""
        if self._request.depth is None and profile.depth:
            return replace(profile, depth=max(profile.depth, READER_CACHE_DEPTH))
        return profile

    def _receiver(self, store_name: str) -> Callable[[bytes], None]:
        """Hands each message's bytes on as `Received`, decoded on demand."""
        store, topic, deliver, clock = self._graph.types.store, self._topic, self._on_message, time.time_ns

        def decode(payload: bytes) -> Any:
            return store.deserialize_cdr(payload, store_name)

        def receive(payload: bytes) -> None:
            deliver(Received(topic, payload, clock(), store_name, decode))

        return receive

    def _offered(self) -> list[QosProfile]:
        return [w.qos for w in self._endpoints() if w.is_writer]

    def _readapted(self, profile: QosProfile) -> QosProfile | None:
        """The QoS that serves every publisher now known, when it differs from `profile`."""
        offered = self._offered()
        if not offered:
            return None
        adapted, notes = adapt_to_publishers(self._request, offered)
        if adapted.reliability == profile.reliability and adapted.durability == profile.durability:
            return None  # the user's own --qos-* choice, or nothing better to do
        for note in notes:
            self._warn(note)
        return adapted

    def _report_incompatible(self, policy: str, profile: QosProfile) -> None:
        """Fatal when no known publisher can serve this reader; otherwise a warning, as ros2 topic echo
        gives, and the compatible publishers keep being read."""
        offered = self._offered()
        described = sorted({qos.describe() for qos in offered})
        offers = f"; publishers offer {'; '.join(described)}" if described else ""
        text = (
            f"a publisher of {self._topic} offers QoS incompatible with this subscription "
            f"({profile.describe()}): incompatible policy {policy}{offers}"
        )
        if offered and not any(serves(qos, profile) for qos in offered):
            self._on_error(f"{text} (adjust --qos-reliability / --qos-durability)")
        else:
            self._warn(f"{text}; no messages will be received from it")
