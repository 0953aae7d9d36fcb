"""ROS 1 services over TCPROS: lookup, probe, a client (one-shot or persistent) and a small server.

A call is: connection header (service, md5sum, callerid), the server's header back, the request as one
length-prefixed frame, then an ok byte and one length-prefixed frame (the response, or an error text).
A `probe=1` header gets only the server's header (its type and md5sum), which is how a service's type
is found: the master does not know it.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.ros1 import tcpros
from rostool.graph.ros1.master_client import RemoteError
from rostool.graph.ros1.names import resolve

if TYPE_CHECKING:
    from rostool.graph.ros1.master_client import MasterClient
    from rostool.graph.ros1.node import Node
    from rostool.interfaces.sources import Interfaces
    from rostool.interfaces.srv import SrvType

DEFAULT_TIMEOUT = 10.0
_OK = struct.Struct("<B")


class ServiceError(RostoolError):
    """The server answered, but with a failure (its handler raised or returned nothing)."""


@dataclass(frozen=True)
class ServiceInfo:
    name: str
    uri: str
    node: str | None
    type: str
    md5sum: str


def parse_rosrpc(uri: str) -> tuple[str, int]:
    prefix = "rosrpc://"
    if not uri.startswith(prefix):
        raise RostoolError(f"invalid service URI {uri!r}: expected rosrpc://host:port")
    host, _, port = uri[len(prefix) :].rstrip("/").rpartition(":")
    if not host or not port.isdigit():
        raise RostoolError(f"invalid service URI {uri!r}: expected rosrpc://host:port")
    return host.strip("[]"), int(port)


def lookup(master: MasterClient, name: str) -> str:
    """The rosrpc:// URI of service `name`; one clear error when no node provides it."""
    name = resolve(name)
    try:
        return master.lookup_service(name)
    except RemoteError as err:
        raise RostoolError(
            f"unknown service {name}: no node provides it (see `rostool service list`)"
        ) from err


def wait_for(master: MasterClient, name: str, timeout: float | None) -> str:
    """Wait until service `name` is registered (like `rosservice call --wait`), then return its URI."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while True:
        try:
            return lookup(master, name)
        except RostoolError:
            if deadline is not None and time.monotonic() >= deadline:
                raise RostoolError(f"service {resolve(name)} did not appear within {timeout:g} s") from None
        time.sleep(0.1)


def services(master: MasterClient) -> list[tuple[str, list[str]]]:
    """(service, providing nodes) for every service the master knows, sorted by name."""
    _publishers, _subscribers, found = master.system_state()
    return sorted((str(name), sorted(nodes)) for name, nodes in found)


def _open(name: str, uri: str, timeout: float | None) -> socket.socket:
    host, port = parse_rosrpc(uri)
    try:
        sock = tcpros.connect(host, port, timeout or DEFAULT_TIMEOUT)
    except ConnectionRefusedError as err:
        raise RostoolError(
            f"service {name} is registered at {uri} but nothing answers there (connection refused); "
            "its server has probably exited without unregistering"
        ) from err
    except OSError as err:
        raise RostoolError(f"cannot connect to service {name} at {uri}: {err}") from err
    sock.settimeout(timeout)
    return sock


def probe(name: str, uri: str, caller_id: str, timeout: float = 5.0) -> dict[str, str]:
    """The server's connection header (type, md5sum, callerid...) without calling it."""
    name = resolve(name)
    sock = _open(name, uri, timeout)
    try:
        sock.sendall(
            tcpros.encode_header({"probe": "1", "md5sum": "*", "callerid": caller_id, "service": name})
        )
        header = tcpros.read_header(sock.makefile("rb"))
    except (OSError, tcpros.ConnectionClosed) as err:
        raise RostoolError(f"service {name} at {uri} closed the connection before saying its type") from err
    finally:
        sock.close()
    if "error" in header:
        raise RostoolError(f"service {name} refused a probe: {header['error']}")
    return header


def service_info(master: MasterClient, name: str) -> ServiceInfo:
    name = resolve(name)
    uri = lookup(master, name)
    header = probe(name, uri, master.caller_id)
    nodes = next((nodes for service, nodes in services(master) if service == name), [])
    return ServiceInfo(
        name, uri, nodes[0] if nodes else None, header.get("type", ""), header.get("md5sum", "")
    )


class ServiceClient:
    """Calls one service; with `persistent` one connection serves every call (TCPROS `persistent=1`)."""

    def __init__(
        self,
        name: str,
        uri: str,
        srv: SrvType,
        caller_id: str,
        persistent: bool = False,
        timeout: float | None = None,
    ) -> None:
        self.name = resolve(name)
        self.uri = uri
        self.srv = srv
        self.caller_id = caller_id
        self.persistent = persistent
        self.timeout = timeout
        self._sock: socket.socket | None = None
        self._stream: tcpros.Readable | None = None

    def __enter__(self) -> ServiceClient:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def call(self, request: object) -> Any:
        return self.srv.response.deserialize(self.call_raw(self.srv.request.serialize(request)))

    def call_raw(self, payload: bytes) -> bytes:
        """Send one serialized request, return the serialized response."""
        sock, stream = self._connection()
        with self._failing(self.close, "before answering (its server exited or crashed)"):
            sock.sendall(tcpros.frame(payload))
            ok = tcpros.read_exact(stream, 1)
            body = tcpros.read_frame(stream)
        if not self.persistent:
            self.close()
        if _OK.unpack(ok)[0] != 1:
            raise ServiceError(f"service {self.name} failed: {body.decode('utf-8', errors='replace')}")
        return body

    def _connection(self) -> tuple[socket.socket, tcpros.Readable]:
        if self._sock is not None and self._stream is not None:
            return self._sock, self._stream
        sock = _open(self.name, self.uri, self.timeout)
        header = {"callerid": self.caller_id, "service": self.name, "md5sum": self.srv.md5sum,
                  "type": self.srv.name}  # fmt: skip
        if self.persistent:
            header["persistent"] = "1"
        stream = sock.makefile("rb", buffering=1 << 16)
        with self._failing(sock.close, "during the handshake"):
            sock.sendall(tcpros.encode_header(header))
            reply = tcpros.read_header(stream)
        if "error" in reply:
            sock.close()
            raise RostoolError(f"service {self.name} refused the call: {reply['error']}")
        self._sock, self._stream = sock, stream
        return sock, stream

    @contextlib.contextmanager
    def _failing(self, close: Callable[[], None], when: str) -> Iterator[None]:
        """A timeout or a lost connection while talking to the server: `close`, then one clear error."""
        try:
            yield
        except TimeoutError as err:
            close()
            raise RostoolError(f"service {self.name} did not answer within {self.timeout:g} s") from err
        except (OSError, tcpros.ConnectionClosed) as err:
            close()
            raise RostoolError(f"service {self.name} closed the connection {when}") from err

    def close(self) -> None:
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.close()
        self._sock = self._stream = None


Handler = Callable[[Any], Any]


class ServiceServer:
    """Provides one service from a Node: registers it and answers calls on the node's TCPROS port."""

    def __init__(self, node: Node, name: str, srv: SrvType, handler: Handler) -> None:
        self.node = node
        self.name = resolve(name)
        self.srv = srv
        self.handler = handler
        self.uri = f"rosrpc://{node.tcpros_host}:{node.tcpros_port}"
        node.service_handlers[self.name] = self._serve
        node.master.register_service(self.name, self.uri, node.uri)

    def _serve(self, sock: socket.socket, header: dict[str, str]) -> None:
        """Runs on the node's handshake thread of one connection."""
        srv = self.srv
        wanted = header.get("md5sum", "*")
        if wanted not in ("*", srv.md5sum):
            caller = header.get("callerid")
            error = f"request from [{caller}]: md5sums do not match: [{wanted}] vs. [{srv.md5sum}]"
            sock.sendall(tcpros.encode_header({"error": error}))
            sock.close()
            return
        sock.sendall(tcpros.encode_header({
            "callerid": self.node.caller_id, "service": self.name, "type": srv.name, "md5sum": srv.md5sum,
            "request_type": srv.request.name, "response_type": srv.response.name,
        }))  # fmt: skip
        if header.get("probe") == "1":
            sock.close()
            return
        persistent = header.get("persistent", "").lower() in ("1", "true")
        sock.settimeout(None)
        stream = sock.makefile("rb")
        try:
            while True:
                payload = tcpros.read_frame(stream)
                sock.sendall(self._answer(payload))
                if not persistent:
                    break
        except (OSError, tcpros.ConnectionClosed):
            pass
        finally:
            sock.close()

    def _answer(self, payload: bytes) -> bytes:
        try:
            response = self.handler(self.srv.request.deserialize(payload))
            if response is None:
                raise RostoolError("service handler returned None")
            return _OK.pack(1) + tcpros.frame(self.srv.response.serialize(response))
        except Exception as err:  # the caller gets the reason, as rospy sends it
            return _OK.pack(0) + tcpros.frame(f"error processing request: {err}".encode())

    def close(self) -> None:
        self.node.service_handlers.pop(self.name, None)
        with contextlib.suppress(RostoolError):
            self.node.master.unregister_service(self.name, self.uri)


def service_type(master: MasterClient, catalog: Interfaces, name: str, uri: str) -> SrvType:
    """The type a running service announces, with its definition from the sources (md5 checked)."""
    from rostool.interfaces.srv import load_service

    name = resolve(name)
    header = probe(name, uri, master.caller_id)
    type_name = header.get("type", "")
    if not type_name:
        raise RostoolError(f"service {name} did not say its type in its connection header")
    srv = load_service(catalog, type_name)
    theirs = header.get("md5sum", "*")
    if theirs not in ("*", srv.md5sum):
        raise RostoolError(
            f"service {name} is a {type_name} with md5sum {theirs}, but the definition in {srv.origin} "
            f"hashes to {srv.md5sum}; point --interfaces at the sources the server was built from"
        )
    return srv


def build_request(srv: SrvType, values: list[Any]) -> Any:
    """The request from one YAML mapping, or from the field values in order (all of them)."""
    from rostool.interfaces.fill import FillError, build_message

    fields = srv.request_spec.fields
    value: Any = values[0] if len(values) == 1 and isinstance(values[0], dict) else values
    if isinstance(value, list) and len(value) != len(fields):
        got = f"got {len(value)}" if value else "got none"
        if not fields:
            raise RostoolError(f"{srv.name} takes no request values; {got}")
        raise RostoolError(
            f"{srv.name} takes {len(fields)} request value(s) in this order: {srv.signature()}; {got}. "
            f'Give them in order or as one YAML mapping, e.g. "{{{fields[0].name}: ...}}"'
        )
    try:
        return build_message(srv.request.store, srv.request.store_name, value)
    except FillError as err:
        raise RostoolError(f"{err} (the request of {srv.name} takes: {srv.signature()})") from err


def call(
    master: MasterClient,
    catalog: Interfaces,
    name: str,
    args: tuple[str, ...],
    wait: bool = False,
    timeout: float | None = None,
) -> tuple[Any, Any]:
    """`rosservice call`: find the service and its type, build the request, call; (request, response)."""
    from rostool.interfaces.values import call_args

    name = resolve(name)
    uri = wait_for(master, name, timeout) if wait else lookup(master, name)
    srv = service_type(master, catalog, name, uri)
    request = build_request(srv, call_args(args))
    with ServiceClient(name, uri, srv, master.caller_id, timeout=timeout) as client:
        return request, client.call(request)
