"""A node's slave XML-RPC API server (how the master and other nodes talk to us)."""

from __future__ import annotations

import os
import threading
from socketserver import ThreadingMixIn
from typing import Any, Protocol
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer


class SlaveHandler(Protocol):
    """What the node behind the slave API provides."""

    caller_id: str
    master_uri: str

    def bus_info(self) -> list[list[Any]]: ...
    def publications(self) -> list[list[str]]: ...
    def subscriptions(self) -> list[list[str]]: ...
    def publisher_update(self, topic: str, publishers: list[str]) -> None: ...
    def request_topic(self, topic: str, protocols: list[list[Any]]) -> list[Any] | None: ...
    def request_shutdown(self, reason: str) -> None: ...
    def param_update(self, key: str, value: Any) -> None: ...


class _QuietHandler(SimpleXMLRPCRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        return


class _Server(ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True
    allow_reuse_address = True


class SlaveServer:
    """Serves the slave API for one node on an ephemeral port."""

    def __init__(self, node: SlaveHandler, bind_host: str, advertised_host: str) -> None:
        self._node = node
        self._server = _Server(
            (bind_host, 0), requestHandler=_QuietHandler, logRequests=False, allow_none=True
        )
        self._server.register_instance(_SlaveApi(node))
        port = self._server.server_address[1]
        self.uri = f"http://{advertised_host}:{port}/"
        self._thread = threading.Thread(target=self._server.serve_forever, name="ros1-slave", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._server.shutdown()
        self._server.server_close()


class _SlaveApi:
    """Method names are the slave API's own (camelCase), dispatched by SimpleXMLRPCServer."""

    def __init__(self, node: SlaveHandler) -> None:
        self._node = node

    def _dispatch(self, method: str, params: tuple[Any, ...]) -> Any:
        handler = getattr(self, "api_" + method, None)
        if handler is None:
            return [-1, f"unknown method {method}", 0]
        return handler(*params[1:]) if params else handler()

    def api_getBusStats(self) -> list[Any]:
        return [1, "", [[], [], []]]

    def api_getBusInfo(self) -> list[Any]:
        return [1, "", self._node.bus_info()]

    def api_getMasterUri(self) -> list[Any]:
        return [1, "", self._node.master_uri]

    def api_getPid(self) -> list[Any]:
        return [1, "", os.getpid()]

    def api_getPublications(self) -> list[Any]:
        return [1, "publications", self._node.publications()]

    def api_getSubscriptions(self) -> list[Any]:
        return [1, "subscriptions", self._node.subscriptions()]

    def api_shutdown(self, reason: str = "") -> list[Any]:
        self._node.request_shutdown(reason)
        return [1, "shutdown", 0]

    def api_publisherUpdate(self, topic: str, publishers: list[str]) -> list[Any]:
        self._node.publisher_update(topic, publishers)
        return [1, "", 0]

    def api_paramUpdate(self, key: str, value: Any) -> list[Any]:
        self._node.param_update(key, value)
        return [1, "", 0]

    def api_requestTopic(self, topic: str, protocols: list[list[Any]]) -> list[Any]:
        answer = self._node.request_topic(topic, protocols)
        if answer is None:
            return [-1, f"not a publisher of {topic} (or no supported protocol)", []]
        return [1, "ready", answer]
