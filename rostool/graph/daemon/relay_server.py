"""The daemon's side of a relay: one client's subscription in the daemon's long-lived graph (already matched
with every publisher it knows), its messages streamed back as wire.py's frames over the client's own
connection until the client goes (it closed, Ctrl+C, kill -9: the connection ends) or the daemon stops.

The subscription's thread only queues (bounded in bytes, the oldest messages dropped first, as the verbs'
own inbox does); a sender thread writes, so a client that reads slowly holds up nothing but itself.
"""

from __future__ import annotations

import contextlib
import json
import logging
import socket
import threading
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import fields
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import Received, Subscription
from rostool.graph.daemon import wire
from rostool.graph.ros2_base.qos import QosRequest
from rostool.graph.ros2_base.relaying import subscribe_for

QUEUE_BYTES = 64 * 1024 * 1024  # a client's messages waiting to be sent
BATCH_BYTES = 1024 * 1024  # frames sent in one write, at most about this much
COALESCE_SECONDS = 0.001
READY_SECONDS = 3.0  # the most a relay waits for its reader to match before it says READY all the same
# the daemon's graph is settled: a topic whose publishers it does not show a moment after the reader was
# asked for is unpublished now (the subscription looks at discovery every 10 ms)
UNPUBLISHED_SECONDS = 0.1
log = logging.getLogger("rostool.daemon")
Frame = tuple[bytes, int, bytes]


def qos_of(value: Any) -> QosRequest:
    """The verb's --qos-* request as the client sent it (unknown keys refused)."""
    names = {f.name for f in fields(QosRequest)}
    if not isinstance(value, dict) or not set(value) <= names:
        raise RostoolError(f"graph daemon: a subscription's QoS must be an object of {sorted(names)}")
    return QosRequest(**value)


class Relay:
    def __init__(self, graph: Any, graph_lock: threading.Lock, connection: socket.socket, topic: str) -> None:
        self.graph = graph
        self.graph_lock = graph_lock
        self.connection = connection
        self.topic = topic
        self._frames: deque[Frame] = deque()
        self._bytes = 0
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._done = threading.Event()
        self._type: str | None = None  # the type the client was last told of
        self._sent_message = False
        self._dropped = 0
        self._subscription: Subscription | None = None

    def open(self, qos: QosRequest) -> None:
        """The daemon's reader of the topic (RostoolError: the client is told in one line)."""
        with self.graph_lock:
            found = subscribe_for(self.graph, self.topic, qos, self._warn, self._put, self._error)
        self._subscription = found

    def run(self) -> None:
        """Stream until the client goes or `stop()`; the reader is closed then."""
        sender = threading.Thread(target=self._send, name=f"relay {self.topic}", daemon=True)
        sender.start()
        try:
            self._say_ready()
            self.connection.settimeout(None)
            while not self._done.is_set():
                try:
                    if not self.connection.recv(4096):  # the client sends nothing more: EOF is its end
                        break
                except OSError:
                    break
        finally:
            self.stop()
            sender.join(5.0)
            if self._subscription is not None:
                self._subscription.close()

    def _say_ready(self) -> None:
        """One READY frame once the reader has matched the publishers the daemon knew when it was made
        (its matched count), or at once when it knows none: a recording's --duration counts from then."""
        subscription, began = self._subscription, time.monotonic()
        wait_matched = getattr(subscription, "wait_matched", None)
        matched = wait_matched is None  # a subscription that cannot tell: ready now
        while not matched and not self._done.is_set() and time.monotonic() - began < READY_SECONDS:
            assert wait_matched is not None
            matched = bool(wait_matched(0.02))
            if not getattr(subscription, "publishers_known", True) and (
                time.monotonic() - began >= UNPUBLISHED_SECONDS
            ):
                break
        self._queue((wire.READY, time.time_ns(), b"1" if matched else b"0"))

    def stop(self) -> None:
        self._done.set()
        self._wake.set()
        with contextlib.suppress(OSError):
            self.connection.shutdown(socket.SHUT_RDWR)

    # --- from the subscription's thread ---------------------------------------------------------
    def _put(self, received: Received) -> None:
        if received.type_name != self._type:
            self._type = received.type_name
            self._queue((wire.TYPE, 0, self._described(received.type_name)))
        self._sent_message = True
        self._queue((wire.MESSAGE, received.recv_time_ns, bytes(received.payload)))

    def _described(self, type_name: str) -> bytes:
        """The type's name and .msg definition (with its nested types): a client that lacks it decodes with
        the daemon's. rosbags writes .msg text for `pkg/msg/` names only, so a type it cannot write (a
        service's event type, `pkg/srv/T_Event`, which the daemon built from sources or learned from the
        service's node) goes as rosbags' field definitions of it and of every type it nests."""
        store = self.graph.types.store
        described: dict[str, Any] = {"name": type_name, "definition": ""}
        try:
            described["definition"] = store.generate_msgdef(type_name, ros_version=2)[0]
        except Exception:
            with contextlib.suppress(Exception):  # neither: the client's own types decide
                described["fielddefs"] = _closure(store.fielddefs, type_name)
        return json.dumps(described).encode()

    def _warn(self, text: str) -> None:
        self._queue((wire.WARNING, time.time_ns(), text.encode()))

    def _error(self, text: str) -> None:
        # before any message: the client subscribes itself (it may know a type the daemon cannot learn)
        kind = wire.ERROR if self._sent_message else wire.DIRECT
        self._queue((kind, time.time_ns(), text.encode()))

    def _queue(self, frame: Frame) -> None:
        size = len(frame[2])
        if size > wire.MAX_SAMPLE:
            frame = (wire.WARNING, frame[1], f"a message of {size} bytes on {self.topic} is over the graph "
                     f"daemon's relay limit ({wire.MAX_SAMPLE} bytes): skipped".encode())  # fmt: skip
        with self._lock:
            self._frames.append(frame)
            self._bytes += len(frame[2])
            while self._bytes > QUEUE_BYTES and len(self._frames) > 1:
                index = next((i for i, f in enumerate(self._frames) if f[0] == wire.MESSAGE), None)
                if index is None:
                    break
                dropped = self._frames[index]
                del self._frames[index]
                self._bytes -= len(dropped[2])
                self._dropped += 1
        if not self._wake.is_set():
            self._wake.set()

    # --- the sender's thread ----------------------------------------------------------------------
    def _send(self) -> None:
        reported = 0
        try:
            while not self._done.is_set():
                if self._wake.wait(0.5):
                    # a moment for more to come: a fast topic's messages go in fewer, larger writes
                    time.sleep(COALESCE_SECONDS)
                self._wake.clear()
                while not self._done.is_set():
                    with self._lock:
                        batch: list[Frame] = []
                        size = 0
                        while self._frames and size < BATCH_BYTES:
                            frame = self._frames.popleft()
                            batch.append(frame)
                            size += len(frame[2])
                        self._bytes -= size
                        dropped = self._dropped
                    if dropped > reported:
                        text = f"the graph daemon dropped {dropped - reported} messages of {self.topic}: " \
                               "they are not read as fast as they come"  # fmt: skip
                        batch.insert(0, (wire.WARNING, time.time_ns(), text.encode()))
                        reported = dropped
                    if not batch:
                        break
                    wire.send_frames(self.connection, batch)
        except wire.WireError as err:
            log.info("relay of %s ended: %s", self.topic, err)
        finally:
            self.stop()


def _closure(fielddefs: Mapping[str, Any], type_name: str) -> dict[str, Any]:
    """`type_name`'s field definitions and those of every type it nests (in JSON: tuples as lists, each
    Nodetype as its number; relay_client.py turns them back)."""
    from rosbags.interfaces import Nodetype

    found: dict[str, Any] = {}
    pending = [type_name]
    while pending:
        name = pending.pop()
        if name in found:
            continue
        found[name] = fielddefs[name]
        for _field, (kind, args) in fielddefs[name][1]:
            element_kind, element = args[0] if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) else (kind, args)
            if element_kind == Nodetype.NAME:
                pending.append(element)
    return found
