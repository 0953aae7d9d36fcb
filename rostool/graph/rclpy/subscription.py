"""A raw rclpy subscription: waits (in its own thread) for the topic's publishers, subscribes with the QoS
adapted to them (as the DDS backend and ros2 topic echo do), and hands on the serialized bytes.

When rmw reports a publisher this subscription cannot match and the QoS was left to rostool, it subscribes
again with the QoS adapted to every publisher now known; otherwise it warns, or fails when no publisher
can serve it, as the DDS backend does.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.base import Received
from rostool.graph.rclpy import types as rtypes
from rostool.graph.rclpy.qos import from_rclpy, to_rclpy
from rostool.graph.ros2 import dds

if TYPE_CHECKING:
    from rostool.graph.rclpy.graph import RclpyGraph

READER_CACHE_DEPTH = 1000  # a deep local history lets a busy moment pass without losing samples
SUBSCRIBERS_ONLY_WAIT = 0.5  # a topic with subscribers only: how long publishers are given to appear


class RclpySubscription:
    def __init__(
        self,
        graph: RclpyGraph,
        topic: str,
        on_message: Callable[[Received], None],
        on_error: Callable[[str], None],
    ) -> None:
        self._graph = graph
        self._topic = topic
        self._on_message = on_message
        self._on_error = on_error
        self._closed = threading.Event()
        self._incompatible = threading.Event()
        self._reader: Any = None
        self._detached = False
        self._thread = threading.Thread(target=self._run, name=f"rclpy sub {topic}", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._closed.set()
        self._incompatible.set()
        if threading.current_thread() is not self._thread:
            self._thread.join(2.0)
        self._drop()

    def _run(self) -> None:
        try:
            chosen = self._wait_for_type()
            if chosen is None:
                return
            store_name, profile = chosen
            cls = rtypes.python_class(store_name)
            while profile is not None and not self._closed.is_set():
                profile = self._read_with(cls, store_name, profile)
        except RostoolError as err:
            self._on_error(str(err))

    def _wait_for_type(self) -> tuple[str, dds.QosProfile] | None:
        graph = self._graph
        started = time.monotonic()
        while not self._closed.is_set():
            pubs, subs = graph._endpoints(self._topic)
            known = pubs or subs
            if known and (pubs or time.monotonic() - started >= SUBSCRIBERS_ONLY_WAIT):
                store_name = graph.store_name(known[0].topic_type)
                offered = [from_rclpy(p.qos_profile) for p in pubs]
                profile, notes = dds.adapt_to_publishers(graph.qos_request, offered)
                for note in notes:
                    graph.warn(note)
                return store_name, profile
            self._closed.wait(0.05)
        return None

    def _read_with(self, cls: Any, store_name: str, profile: dds.QosProfile) -> dds.QosProfile | None:
        """Subscribe with `profile` until closed, or until a publisher it cannot match calls for another."""
        from rclpy.event_handler import SubscriptionEventCallbacks

        graph = self._graph
        cache_profile = profile
        if graph.qos_request.depth is None and profile.depth:
            cache_profile = replace(profile, depth=max(profile.depth, READER_CACHE_DEPTH))
        store, topic, deliver, clock = graph.types.store, self._topic, self._on_message, time.time_ns

        def decode(payload: bytes) -> Any:
            return store.deserialize_cdr(payload, store_name)

        def on_bytes(payload: bytes) -> None:
            deliver(Received(topic, payload, clock(), store_name, decode))

        events = SubscriptionEventCallbacks(incompatible_qos=self._on_incompatible)
        self._incompatible.clear()
        self._reader = graph.node.create_subscription(
            cls, topic, on_bytes, to_rclpy(cache_profile), raw=True, event_callbacks=events
        )
        taking = self._detach(self._reader)
        while not self._closed.is_set():
            if taking:
                self._take_until_event(self._reader, cls, on_bytes)
            else:
                self._incompatible.wait()
            if self._closed.is_set():
                break
            self._incompatible.clear()
            adapted = self._readapted(profile)
            if adapted is not None:
                self._drop()
                return adapted
            self._report_incompatible(profile)
        return None

    def _detach(self, reader: Any) -> bool:
        """Serve this subscription (its messages and its QoS events) in this thread instead of the
        executor's: it waits once for a batch and takes every message there is, where rclpy's executor
        rebuilds its wait set for each message. False where rclpy's internals differ from Jazzy's and
        Kilted's: the executor serves it then."""
        try:
            from rclpy.impl.implementation_singleton import rclpy_implementation

            handlers = list(reader.event_handlers)
            context = self._graph.context.context.handle
            self._wait_set = rclpy_implementation.WaitSet(1, 0, 0, 0, 0, len(handlers), context)
            node = self._graph.node
            node._subscriptions.remove(reader)
            for handler in handlers:
                node.remove_waitable(handler)
        except Exception:
            return False
        self._detached = True
        return True

    def _take_until_event(self, reader: Any, cls: Any, on_bytes: Callable[[bytes], None]) -> None:
        """Take messages as they come, and run the QoS event callbacks, until closed or a QoS event calls
        for a look."""
        wait_set, handle, handlers = self._wait_set, reader.handle, list(reader.event_handlers)
        with contextlib.ExitStack() as held:  # in use: not destroyed while waited on
            held.enter_context(handle)
            for handler in handlers:
                held.enter_context(handler)
            while not self._incompatible.is_set():
                wait_set.clear_entities()
                wait_set.add_subscription(handle)
                for handler in handlers:
                    handler.add_to_wait_set(wait_set)
                wait_set.wait(100_000_000)  # 0.1 s: close is noticed in time
                for handler in handlers:
                    if handler.is_ready(wait_set):
                        data = handler.take_data()
                        if data and handler.callback is not None:
                            handler.callback(data)
                if not wait_set.get_ready_entities("subscription"):
                    continue
                while True:
                    taken = handle.take_message(cls, True)
                    if taken is None:
                        break
                    on_bytes(taken[0])

    def _on_incompatible(self, event: Any) -> None:
        self._policy = getattr(getattr(event, "last_policy_kind", None), "name", "?")
        self._incompatible.set()

    def _offered(self) -> list[dds.QosProfile]:
        return [from_rclpy(p.qos_profile) for p in self._graph._endpoints(self._topic)[0]]

    def _readapted(self, profile: dds.QosProfile) -> dds.QosProfile | None:
        offered = self._offered()
        if not offered:
            return None
        adapted, notes = dds.adapt_to_publishers(self._graph.qos_request, offered)
        if adapted.reliability == profile.reliability and adapted.durability == profile.durability:
            return None
        for note in notes:
            self._graph.warn(note)
        return adapted

    def _report_incompatible(self, profile: dds.QosProfile) -> None:
        offered = self._offered()
        described = sorted({qos.describe() for qos in offered})
        offers = f"; publishers offer {'; '.join(described)}" if described else ""
        policy = getattr(self, "_policy", "?").removesuffix("_QOS_POLICY")
        text = (
            f"a publisher of {self._topic} offers QoS incompatible with this subscription "
            f"({profile.describe()}): incompatible policy {policy}{offers}"
        )
        if offered and not any(dds.serves(qos, profile) for qos in offered):
            self._on_error(f"{text} (adjust --qos-reliability / --qos-durability)")
        else:
            self._graph.warn(f"{text}; no messages will be received from it")

    def _drop(self) -> None:
        reader, self._reader = self._reader, None
        if reader is not None:
            try:
                if self._detached:  # the node destroys only what it lists
                    self._detached = False
                    self._graph.node._subscriptions.append(reader)
                    for handler in reader.event_handlers:
                        self._graph.node.add_waitable(handler)
                self._graph.node.destroy_subscription(reader)
            except Exception:  # the context is already shut down: rclpy destroyed it
                return
