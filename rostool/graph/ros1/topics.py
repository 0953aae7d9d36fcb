"""TCPROS topic transport: our publishers' outbound links and our subscriptions' inbound links."""

from __future__ import annotations

import contextlib
import itertools
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from rostool.errors import RostoolError
from rostool.graph.ros1 import tcpros
from rostool.graph.ros1.master_client import RemoteError, Unreachable, call
from rostool.interfaces.ros1 import Ros1Type

_connection_ids = itertools.count(1)
SEND_TIMEOUT = 5.0
RECONNECT_FIRST = 0.1  # seconds before connecting again to a publisher whose link dropped; doubles
RECONNECT_MAX = 2.0


@dataclass
class OutboundLink:
    """One subscriber connected to one of our publishers."""

    sock: socket.socket
    caller_id: str
    id: int = field(default_factory=lambda: next(_connection_ids))


class Publisher:
    """Publishes one topic to every connected subscriber; keeps the last message when latched."""

    def __init__(self, topic: str, msg_type: Ros1Type, caller_id: str, latch: bool) -> None:
        self.topic = topic
        self.type = msg_type
        self.latch = latch
        self._caller_id = caller_id
        self._links: list[OutboundLink] = []
        self._lock = threading.Lock()
        self._latched: bytes | None = None
        self._connected = threading.Condition(self._lock)

    def reply_header(self) -> dict[str, str]:
        return {
            "callerid": self._caller_id,
            "topic": self.topic,
            "type": self.type.name,
            "md5sum": self.type.md5sum,
            "message_definition": self.type.definition,
            "latching": "1" if self.latch else "0",
        }

    def accept(self, sock: socket.socket, header: dict[str, str]) -> None:
        """Handshake with a subscriber that connected to our TCPROS port."""
        wanted = header.get("md5sum", "*")
        if wanted not in ("*", self.type.md5sum):
            error = (
                f"message type mismatch on {self.topic}: subscriber wants {header.get('type')} "
                f"md5 {wanted}, publisher has {self.type.name} md5 {self.type.md5sum}"
            )
            sock.sendall(tcpros.encode_header({"error": error}))
            sock.close()
            return
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(SEND_TIMEOUT)
        link = OutboundLink(sock, header.get("callerid", ""))
        with self._lock:
            sock.sendall(tcpros.encode_header(self.reply_header()))
            if self.latch and self._latched is not None:
                sock.sendall(self._latched)
            self._links.append(link)
            self._connected.notify_all()

    def publish(self, message: object) -> None:
        self.publish_raw(self.type.serialize(message))

    def publish_raw(self, payload: bytes | memoryview) -> None:
        data = tcpros.frame(payload)
        with self._lock:
            if self.latch:
                self._latched = data
            dead = []
            for link in self._links:
                try:
                    link.sock.sendall(data)
                except OSError:
                    dead.append(link)
            for link in dead:
                self._drop(link)

    def _drop(self, link: OutboundLink) -> None:
        self._links.remove(link)
        link.sock.close()

    @property
    def subscriber_count(self) -> int:
        with self._lock:
            return len(self._links)

    def wait_for_subscribers(self, count: int, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        with self._lock:
            while len(self._links) < count:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                self._connected.wait(remaining)
            return True

    def links(self) -> list[OutboundLink]:
        with self._lock:
            return list(self._links)

    def close(self) -> None:
        with self._lock:
            for link in list(self._links):
                self._drop(link)


MessageCallback = Callable[[bytes, "InboundLink"], None]
ErrorCallback = Callable[[str], None]


class InboundLink:
    """Our connection to one publisher of a subscribed topic; reads frames on its own thread."""

    def __init__(self, subscription: Subscription, publisher_uri: str) -> None:
        self.subscription = subscription
        self.publisher_uri = publisher_uri
        self.header: dict[str, str] = {}
        self.id = next(_connection_ids)
        self.connected = False
        self._sock: socket.socket | None = None
        self._closed = False
        self._gave_up = False  # the publisher refused us: no retry
        self._retry = threading.Event()  # set by close(): stop waiting to reconnect
        self._thread = threading.Thread(target=self._run, name=f"tcpros-in {publisher_uri}", daemon=True)
        self._thread.start()

    @property
    def publisher_id(self) -> str:
        return self.header.get("callerid", self.publisher_uri)

    def _run(self) -> None:
        """Connect and read; when the link drops while the publisher is still listed (a publisher restarted
        on the same URI, a network hiccup), connect again with backoff, as rospy does, until the
        subscription closes the link (the master said the publisher left, or we stop)."""
        backoff = RECONNECT_FIRST
        try:
            while not self._closed:
                if self._serve():
                    backoff = RECONNECT_FIRST  # it worked for a while: start over quickly next time
                if self._closed or self._gave_up:
                    return
                self._retry.wait(backoff)
                backoff = min(backoff * 2, RECONNECT_MAX)
        finally:
            self.connected = False
            self.close()

    def _serve(self) -> bool:
        """One connection's life; whether it got as far as the handshake."""
        sub = self.subscription
        try:
            self._sock = self._connect()
            self._sock.sendall(tcpros.encode_header(sub.request_header()))
            self.header = tcpros.read_handshake(self._sock)
            self._sock.settimeout(None)
            stream = self._sock.makefile("rb", buffering=1 << 16)
            if "error" in self.header:
                error = self.header["error"]
                sub.report_error(f"publisher {self.publisher_uri} refused {sub.topic}: {error}")
                self._gave_up = True
                return True
            self.connected = True
            callback = sub.callback
            read_frame = tcpros.read_frame
            while not self._closed:
                callback(read_frame(stream), self)
        except (tcpros.ConnectionClosed, OSError, Unreachable, RemoteError):
            pass  # the publisher died, left or restarts (not yet publishing): retried until the master
            # says it is gone
        except RostoolError as err:
            if not self._closed:
                sub.report_error(str(err))
            self._gave_up = True
        finally:
            handshaken = self.connected
            self.connected = False
            self._drop_socket()
        return handshaken

    def _connect(self) -> socket.socket:
        protocol = call(
            self.publisher_uri,
            "requestTopic",
            self.subscription.caller_id,
            self.subscription.topic,
            [["TCPROS"]],
            what=f"the publisher of {self.subscription.topic}",
        )
        if not protocol or protocol[0] != "TCPROS":
            raise RostoolError(f"publisher {self.publisher_uri} offers no TCPROS connection")
        host, port = str(protocol[1]), int(protocol[2])
        return tcpros.connect(host, port)

    def close(self) -> None:
        self._closed = True
        self._retry.set()
        self._drop_socket()

    def _drop_socket(self) -> None:
        sock = self._sock
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()


class Subscription:
    """A subscription to one topic: one inbound link per publisher, kept in step with the master."""

    def __init__(
        self,
        topic: str,
        caller_id: str,
        callback: MessageCallback,
        msg_type: Ros1Type | None = None,
        on_error: ErrorCallback | None = None,
    ) -> None:
        self.topic = topic
        self.caller_id = caller_id
        self.callback = callback
        self.type = msg_type
        self._on_error = on_error
        self._links: dict[str, InboundLink] = {}
        self._lock = threading.Lock()

    @property
    def type_name(self) -> str:
        return self.type.name if self.type else "*"

    def request_header(self) -> dict[str, str]:
        msg_type = self.type
        return {
            "callerid": self.caller_id,
            "topic": self.topic,
            "md5sum": msg_type.md5sum if msg_type else "*",
            "type": msg_type.name if msg_type else "*",
            "message_definition": msg_type.definition if msg_type else "",
            "tcp_nodelay": "1",
        }

    def update_publishers(self, uris: list[str]) -> None:
        with self._lock:
            wanted = set(uris)
            for uri in list(self._links):
                if uri not in wanted:
                    self._links.pop(uri).close()
            for uri in uris:
                if uri not in self._links:
                    self._links[uri] = InboundLink(self, uri)

    def links(self) -> list[InboundLink]:
        with self._lock:
            return list(self._links.values())

    def report_error(self, message: str) -> None:
        if self._on_error is not None:
            self._on_error(message)

    def close(self) -> None:
        with self._lock:
            for link in self._links.values():
                link.close()
            self._links.clear()
