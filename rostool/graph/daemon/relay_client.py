"""The verb's side of a relay: a subscription whose reader lives in the graph daemon (already matched with the
topic's publishers, so the first message comes without this process joining the graph), its messages
read from the daemon's frames and decoded with this process's types, as a direct subscription hands them
on (`Received`: CDR bytes, the daemon's receive time, the type).

When the daemon cannot serve it (it failed before the first message: a type it cannot learn, a QoS no
publisher serves) or goes away mid-stream, the verb subscribes itself (`direct()`), so no message source
is lost for good; the latter says so in one warning line.
"""

from __future__ import annotations

import contextlib
import json
import socket
import threading
from collections.abc import Callable
from typing import Any

from rostool.graph.base import OnError, OnMessage, Received, Subscription
from rostool.graph.daemon import wire
from rostool.interfaces.ros2_types import Ros2Types

Warn = Callable[[str], None]
STREAM_BUFFER = 256 * 1024  # the connection's read buffer: a batch of small frames in one system call


class RelayedSubscription:
    def __init__(
        self, sock: socket.socket, topic: str, types: Ros2Types, on_message: OnMessage, on_error: OnError,
        warn: Warn, direct: Callable[[], Subscription],
    ) -> None:  # fmt: skip
        self._sock = sock
        self._topic = topic
        self._types = types
        self._on_message = on_message
        self._on_error = on_error
        self._warn = warn
        self._direct = direct
        self._inner: Subscription | None = None
        self._closed = threading.Event()
        # set when the daemon's reader matched the publishers it knew (or knew none), on the first message,
        # or when this process subscribes itself: `bag record`'s wait before its --duration clock
        self.ready = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._read, name=f"relayed {topic}", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._closed.set()
        with contextlib.suppress(OSError):
            self._sock.shutdown(socket.SHUT_RDWR)
        if threading.current_thread() is not self._thread:
            self._thread.join(2.0)
        self._sock.close()
        with self._lock:
            inner, self._inner = self._inner, None
        if inner is not None:
            inner.close()

    def _read(self) -> None:
        topic, deliver = self._topic, self._on_message
        stream = self._sock.makefile("rb", buffering=STREAM_BUFFER)
        type_name = ""
        store = self._types.store
        decoder = _decoder(store, type_name)
        try:
            while not self._closed.is_set():
                kind, stamp, payload = wire.receive_frame(stream)
                if kind == wire.MESSAGE:
                    deliver(Received(topic, payload, stamp, type_name, decoder))
                    if not self.ready.is_set():
                        self.ready.set()
                elif kind == wire.READY:
                    self.ready.set()
                elif kind == wire.TYPE:
                    type_name = self._learn(payload)
                    decoder = _decoder(store, type_name)
                elif kind == wire.WARNING:
                    self._warn(payload.decode(errors="replace"))
                elif kind == wire.ERROR:
                    self._on_error(payload.decode(errors="replace"))
                elif kind == wire.DIRECT:
                    self._go_direct()
                    return
        except wire.WireError as err:
            if not self._closed.is_set():
                self._warn(f"the graph daemon stopped relaying {topic} ({err}); subscribing directly")
                self._go_direct()
        finally:
            stream.close()  # it holds the socket open too

    def _learn(self, payload: bytes) -> str:
        """The type the daemon reads, made known to this process's store from the daemon's definition
        when this process lacks it (a type the daemon learned from its publisher): its .msg text, or for a
        type rosbags cannot write as one (a service's event type) its field definitions."""
        described = json.loads(payload)
        name, text = str(described["name"]), str(described.get("definition") or "")
        fielddefs = described.get("fielddefs")
        if not self._types.in_store(name):
            with contextlib.suppress(Exception):  # unparsable: this process's own sources may know it
                if fielddefs:
                    self._types.register(_fielddefs_from_json(fielddefs))
                elif text:
                    from rosbags.typesys import get_types_from_msg

                    self._types.register(get_types_from_msg(text, name))
        if not self._types.in_store(name):
            with contextlib.suppress(Exception):  # a broken source file: the decoder names the type
                self._types.knows(name)  # from this process's sources (an event type built from them)
        return name

    def _go_direct(self) -> None:
        self.ready.set()  # the direct subscription's own start is not waited for
        with self._lock:
            if self._closed.is_set():
                return
            self._inner = self._direct()


def _decoder(store: Any, type_name: str) -> Callable[[bytes], Any]:
    def decode(payload: bytes) -> Any:
        return store.deserialize_cdr(payload, type_name)

    return decode


def _fielddefs_from_json(found: dict[str, Any]) -> dict[str, Any]:
    """rosbags' `{name: (consts, fields)}` from relay_server's JSON of it (lists back to tuples, numbers
    back to Nodetype: rosbags compares definitions as tuples)."""
    from rosbags.interfaces import Nodetype

    def desc(value: Any) -> Any:
        kind, args = Nodetype(value[0]), value[1]
        if kind == Nodetype.NAME:
            return (kind, str(args))
        if kind == Nodetype.BASE:
            return (kind, (str(args[0]), int(args[1])))
        return (kind, (desc(args[0]), int(args[1])))

    return {
        name: ([tuple(const) for const in consts], [(str(field), desc(value)) for field, value in fields])
        for name, (consts, fields) in found.items()
    }
