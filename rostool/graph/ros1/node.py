"""A native ROS 1 node: registers with the master, serves the slave API and TCPROS."""

from __future__ import annotations

import _thread
import contextlib
import socket
import threading
from collections.abc import Callable
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.ros1 import env, tcpros
from rostool.graph.ros1.master_client import MasterClient
from rostool.graph.ros1.names import anonymous as anonymous_name
from rostool.graph.ros1.names import resolve
from rostool.graph.ros1.slave import SlaveServer
from rostool.graph.ros1.topics import ErrorCallback, MessageCallback, Publisher, Subscription
from rostool.interfaces.ros1 import Ros1Type

UNREGISTER_BUDGET = 1.0  # seconds closing may spend unregistering from the master

ServiceHandler = Callable[[socket.socket, dict[str, str]], None]  # one connection, its header


class Node:
    """One node in the graph. Use as a context manager so registrations are always removed."""

    def __init__(self, name: str = "rostool", anonymous: bool = True) -> None:
        self.caller_id = anonymous_name(name) if anonymous else resolve(name)
        self.master_uri = env.master_uri()
        self.master = MasterClient(self.master_uri, self.caller_id)
        self._publishers: dict[str, Publisher] = {}
        self._subscriptions: dict[str, Subscription] = {}
        self.service_handlers: dict[str, ServiceHandler] = {}
        self._lock = threading.Lock()
        self._closed = False
        self.shutdown_reason: str | None = None
        host, bind = env.advertised_host(), env.bind_host()
        self._listener = socket.create_server((bind, 0))
        self.tcpros_host, self.tcpros_port = host, self._listener.getsockname()[1]
        self.slave = SlaveServer(self, bind, host)
        self.uri = self.slave.uri
        threading.Thread(target=self._accept_loop, name="tcpros-accept", daemon=True).start()

    def __enter__(self) -> Node:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    # --- topics -------------------------------------------------------------------------------
    def advertise(self, topic: str, msg_type: Ros1Type, latch: bool = False) -> Publisher:
        topic = resolve(topic)
        publisher = Publisher(topic, msg_type, self.caller_id, latch)
        with self._lock:
            self._publishers[topic] = publisher
        self.master.register_publisher(topic, msg_type.name, self.uri)
        return publisher

    def subscribe(
        self,
        topic: str,
        callback: MessageCallback,
        msg_type: Ros1Type | None = None,
        on_error: ErrorCallback | None = None,
    ) -> Subscription:
        """Subscribe; with no msg_type any publisher's type is accepted (md5 `*`), as rostopic does."""
        topic = resolve(topic)
        subscription = Subscription(topic, self.caller_id, callback, msg_type, on_error)
        with self._lock:
            self._subscriptions[topic] = subscription
        publishers = self.master.register_subscriber(topic, subscription.type_name, self.uri)
        subscription.update_publishers(publishers)
        return subscription

    # --- slave API callbacks ------------------------------------------------------------------
    def bus_info(self) -> list[list[Any]]:
        info: list[list[Any]] = []
        with self._lock:
            publishers = list(self._publishers.values())
            subscriptions = list(self._subscriptions.values())
        for pub in publishers:
            info.extend([link.id, link.caller_id, "o", "TCPROS", pub.topic, True, ""] for link in pub.links())
        for sub in subscriptions:
            info.extend(
                [link.id, link.publisher_uri, "i", "TCPROS", sub.topic, link.connected, ""]
                for link in sub.links()
            )
        return info

    def publications(self) -> list[list[str]]:
        with self._lock:
            return [[topic, pub.type.name] for topic, pub in self._publishers.items()]

    def subscriptions(self) -> list[list[str]]:
        with self._lock:
            return [[topic, sub.type_name] for topic, sub in self._subscriptions.items()]

    def publisher_update(self, topic: str, publishers: list[str]) -> None:
        with self._lock:
            subscription = self._subscriptions.get(topic)
        if subscription is not None:
            subscription.update_publishers(publishers)

    def request_topic(self, topic: str, protocols: list[list[Any]]) -> list[Any] | None:
        with self._lock:
            known = topic in self._publishers
        if not known or not any(p and p[0] == "TCPROS" for p in protocols):
            return None
        return ["TCPROS", self.tcpros_host, self.tcpros_port]

    def request_shutdown(self, reason: str) -> None:
        """`rosnode kill`: end the program the way Ctrl+C would, so every `finally` runs."""
        self.shutdown_reason = reason or "shutdown requested"
        _thread.interrupt_main()

    def param_update(self, key: str, value: Any) -> None:
        return

    # --- TCPROS listener ----------------------------------------------------------------------
    def _accept_loop(self) -> None:
        while not self._closed:
            try:
                sock, _addr = self._listener.accept()
            except OSError:
                return
            threading.Thread(target=self._handshake, args=(sock,), daemon=True).start()

    def _handshake(self, sock: socket.socket) -> None:
        try:
            header = tcpros.read_handshake(sock)
            sock.settimeout(5.0)
        except (OSError, tcpros.ConnectionClosed):
            sock.close()
            return
        try:
            if "topic" in header:
                with self._lock:
                    publisher = self._publishers.get(header["topic"])
                if publisher is None:
                    sock.sendall(tcpros.encode_header({"error": f"no publisher for {header['topic']}"}))
                    sock.close()
                    return
                publisher.accept(sock, header)
            elif "service" in header and header["service"] in self.service_handlers:
                self.service_handlers[header["service"]](sock, header)
            else:
                sock.close()
        except OSError:
            sock.close()

    # --- shutdown -----------------------------------------------------------------------------
    def close(self) -> None:
        """Unregister everything from the master and close every connection (idempotent)."""
        if self._closed:
            return
        self._closed = True
        with self._lock:
            publishers = list(self._publishers.values())
            subscriptions = list(self._subscriptions.values())
            self._publishers.clear()
            self._subscriptions.clear()
        for sub in subscriptions:  # nothing more arrives from here on
            sub.close()

        def unregister() -> None:
            for sub in subscriptions:
                with contextlib.suppress(RostoolError):
                    self.master.unregister_subscriber(sub.topic, self.uri)
            for pub in publishers:
                with contextlib.suppress(RostoolError):
                    self.master.unregister_publisher(pub.topic, self.uri)

        # A courtesy to the master, within a budget: a master that hangs (stopped, overloaded) must not
        # hold up Ctrl+C; it drops a node whose API no longer answers by itself.
        if subscriptions or publishers:
            courtesy = threading.Thread(target=unregister, name="ros1-unregister", daemon=True)
            courtesy.start()
            courtesy.join(UNREGISTER_BUDGET)
        for pub in publishers:
            pub.close()
        with contextlib.suppress(OSError):
            self._listener.close()
        self.slave.close()
