"""A raw rclpy subscription: the shared draining subscription (ros2_base/subscription.py) reading
serialized messages through rclpy, in its own thread where rclpy's internals allow it."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostool.graph.rclpy import types as rtypes
from rostool.graph.rclpy.qos import to_rclpy
from rostool.graph.ros2_base.subscription import DrainingSubscription

if TYPE_CHECKING:
    from rostool.graph.rclpy.host import RclpyHost
    from rostool.graph.ros2_base.qos import QosProfile
    from rostool.graph.ros2_base.transport import EndpointView


class RclpySubscription(DrainingSubscription):
    thread_name = "rclpy sub"
    _graph: RclpyHost

    def _setup(self) -> None:
        self._incompatible = threading.Event()
        self._reader: Any = None
        self._detached = False
        self._policy = "?"

    def _wake(self) -> None:
        self._incompatible.set()

    def _known_type(self, type_name: str, writers: list[EndpointView]) -> str:
        return self._graph.store_name(type_name)

    def _read_with(self, store_name: str, profile: QosProfile) -> QosProfile | None:
        """Subscribe with `profile` until closed, or until a publisher it cannot match calls for another."""
        from rclpy.event_handler import SubscriptionEventCallbacks

        graph = self._graph
        cls = rtypes.python_class(store_name)
        on_bytes = self._receiver(store_name)
        events = SubscriptionEventCallbacks(incompatible_qos=self._on_incompatible)
        self._incompatible.clear()
        self._reader = graph.node.create_subscription(
            cls,
            self._topic,
            on_bytes,
            to_rclpy(self._cache_profile(profile)),
            raw=True,
            event_callbacks=events,
        )
        taking = self._detach(self._reader)
        watch = self._static_type is not None  # until its first message: publishers of another type
        while not self._closed.is_set():
            if taking:
                self._take_until_event(self._reader, cls, on_bytes, watch)
            else:
                self._incompatible.wait()
            if self._closed.is_set():
                break
            self._incompatible.clear()
            adapted = self._readapted(profile)
            if adapted is not None:
                self._drop()
                return adapted
            self._report_incompatible(self._policy.removesuffix("_QOS_POLICY"), profile)
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

    def _take_until_event(
        self, reader: Any, cls: Any, on_bytes: Callable[[bytes], None], watch: bool = False
    ) -> None:
        """Take messages as they come, and run the QoS event callbacks, until closed or a QoS event calls
        for a look; with `watch` (a static topic), look for publishers of another type until a message
        comes."""
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
                    if watch:
                        self._static_writer_known()  # warns about publishers of another type
                    continue
                watch = False
                while True:
                    taken = handle.take_message(cls, True)
                    if taken is None:
                        break
                    on_bytes(taken[0])

    def _matched_count(self) -> int | None:
        try:
            return int(self._reader.get_publisher_count())
        except Exception:  # no reader (yet, or any more: destroyed with its node)
            return None

    def _on_incompatible(self, event: Any) -> None:
        self._policy = getattr(getattr(event, "last_policy_kind", None), "name", "?")
        self._incompatible.set()

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
