"""The daemon's side of service calls made for a verb (parameters, `service call`, lifecycle, logger levels):
the daemon's graph already knows every server, so a client it makes matches in milliseconds, and a client
it keeps answers the next call at once; the verb's process never joins the graph.

Requests (wire.py's JSON): {"op": "call_open", "service", "type"} -> the request and response type names
with rosbags' field definitions of them and of what they nest (the verb registers those it lacks);
{"op": "call_wait", ..., "timeout"} -> whether a server matched; {"op": "call", ..., "request": CDR
(base64), "timeout", "forever"} -> the reply's CDR (base64). A backend's one-line error (no server, a
timeout, a type nobody describes) is the answer's "error", raised in the verb as it would be raised there.

Clients are pooled per (service, type): one call at a time each (a Fast DDS server's replies are paired
with requests only that way: ros2/services.py), a second client while one is busy, and an idle one is
closed after IDLE_SECONDS, so the daemon's node does not stay a client of every service it was asked to
call (`service info` shows it meanwhile, as it shows any client).
"""

from __future__ import annotations

import base64
import contextlib
import threading
import time
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.daemon.relay_server import _closure

IDLE_SECONDS = 10.0  # an idle client of the daemon's is closed after this long
KEEP_IDLE = 2  # idle clients kept per (service, type)
Key = tuple[str, str]


class Calls:
    def __init__(self, graph: Any, graph_lock: threading.Lock) -> None:
        self._graph = graph
        self._graph_lock = graph_lock
        self._idle: dict[Key, list[tuple[float, Any]]] = {}
        self._lock = threading.Lock()

    def answer(self, request: dict[str, Any]) -> dict[str, Any]:
        op, service, srv_type = request.get("op"), request.get("service"), request.get("type")
        if not isinstance(service, str) or not isinstance(srv_type, str):
            return {"error": "graph daemon: a call names its service and type"}
        try:
            if op == "call_open":
                return {"ok": self._open((service, srv_type))}
            timeout = float(request.get("timeout", 5.0))
            if op == "call_wait":
                return {"ok": self._use((service, srv_type), lambda c: bool(c.wait_for_server(timeout)))}
            payload = base64.b64decode(str(request.get("request", "")))
            forever = bool(request.get("forever", False))
            return {"ok": self._use((service, srv_type), lambda c: self._call(c, payload, timeout, forever))}
        except RostoolError as err:
            return {"error": str(err)}

    def _open(self, key: Key) -> dict[str, Any]:
        def described(client: Any) -> dict[str, Any]:
            request = str(client.request_type)
            response = request.removesuffix("_Request") + "_Response"
            fielddefs = self._graph.types.store.fielddefs
            # rosbags' own field definitions, not .msg text: the text loses a `byte` and a `char` to
            # `uint8` (a request printed `byte_value=0` where the direct way prints `b'\x00'`)
            found = {**_closure(fielddefs, request), **_closure(fielddefs, response)}
            return {"request": request, "response": response, "fielddefs": found}

        return self._use(key, described)  # type: ignore[no-any-return]

    def _call(self, client: Any, payload: bytes, timeout: float, forever: bool) -> str:
        store = self._graph.types.store
        request_type = str(client.request_type)
        try:
            request = store.deserialize_cdr(payload, request_type)
        except Exception as err:
            raise RostoolError(f"graph daemon: cannot read the request of {client.service}: {err}") from None
        reply = client.call(request, timeout, forever)
        response_type = request_type.removesuffix("_Request") + "_Response"
        return base64.b64encode(bytes(store.serialize_cdr(reply, response_type))).decode()

    def _use(self, key: Key, use: Any) -> Any:
        client = self._take(key)
        try:
            return use(client)
        finally:
            self._give(key, client)

    def _take(self, key: Key) -> Any:
        with self._lock:
            idle = self._idle.get(key)
            if idle:
                return idle.pop()[1]
        with self._graph_lock:  # making endpoints beside a query's look at discovery
            return self._graph.service_client(key[0], key[1])

    def _give(self, key: Key, client: Any) -> None:
        with self._lock:
            idle = self._idle.setdefault(key, [])
            if len(idle) < KEEP_IDLE:
                idle.append((time.monotonic(), client))
                return
        _close(client)

    def sweep(self) -> None:
        """Close the clients idle for IDLE_SECONDS (called from the daemon's poll)."""
        now, old = time.monotonic(), []
        with self._lock:
            for key, idle in list(self._idle.items()):
                old.extend(client for since, client in idle if now - since >= IDLE_SECONDS)
                idle[:] = [(since, client) for since, client in idle if now - since < IDLE_SECONDS]
                if not idle:
                    del self._idle[key]
        for client in old:
            _close(client)

    def close(self) -> None:
        with self._lock:
            clients = [client for idle in self._idle.values() for _since, client in idle]
            self._idle.clear()
        for client in clients:
            _close(client)


def _close(client: Any) -> None:
    with contextlib.suppress(Exception):  # the graph is closing already
        client.close()
