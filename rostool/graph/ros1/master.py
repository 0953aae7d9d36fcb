"""An embedded ROS 1 master and parameter server (what `roscore` runs), in pure Python.

    master = Master(port=11311)
    uri = master.start()          # http://127.0.0.1:11311/
    master.wait()                 # until stop() or an XML-RPC shutdown call
    master.stop()

The XML-RPC server handles each connection in its own daemon thread (HTTP/1.1 keep-alive, as rosmaster),
never logs requests, and sends node callbacks from background threads (see master_notify).
"""

from __future__ import annotations

import contextlib
import errno
import os
import socket
import socketserver
import threading
import uuid
from types import TracebackType
from typing import Any
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

from rostool.errors import RostoolError
from rostool.graph.ros1.env import MASTER_HOST, MASTER_PORT, served_name
from rostool.graph.ros1.master_api import MasterApi

DEFAULT_DISTRO = "noetic"
ROS_VERSION = "1.16.0"  # ros_comm version of the last ROS 1 release (Noetic)


class _RequestHandler(SimpleXMLRPCRequestHandler):
    protocol_version = "HTTP/1.1"
    rpc_paths = ()  # any path: clients post to / or /RPC2

    def log_message(self, format: str, *args: Any) -> None:
        pass


class _Server(socketserver.ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True
    block_on_close = False
    allow_reuse_address = True
    request_queue_size = socket.SOMAXCONN

    def __init__(self, address: tuple[str, int], family: socket.AddressFamily) -> None:
        self.address_family = family
        self._connections: set[socket.socket] = set()
        self._connections_lock = threading.Lock()
        super().__init__(address, _RequestHandler, logRequests=False, allow_none=False)
        self.register_multicall_functions()  # rospy and roslaunch batch calls with system.multicall

    def process_request(self, request: Any, client_address: Any) -> None:
        with self._connections_lock:
            self._connections.add(request)
        super().process_request(request, client_address)

    def shutdown_request(self, request: Any) -> None:
        with self._connections_lock:
            self._connections.discard(request)
        super().shutdown_request(request)

    def close_connections(self) -> None:
        """End kept-alive connections so no client keeps talking to a stopped master."""
        with self._connections_lock:
            connections = list(self._connections)
        for connection in connections:
            with contextlib.suppress(OSError):
                connection.shutdown(socket.SHUT_RDWR)

    def handle_error(self, request: Any, client_address: Any) -> None:
        # A client that hangs up mid-request is not worth a traceback on the console.
        pass


def core_params() -> dict[str, str]:
    """The parameters roscore sets, with roslaunch's convention (command output, newline included).

    /rosdistro is what `rosversion -d` prints: $ROS_DISTRO when set.
    """
    distro = os.environ.get("ROS_DISTRO", "").strip() or DEFAULT_DISTRO
    return {"/rosdistro": distro + "\n", "/rosversion": ROS_VERSION + "\n", "/run_id": str(uuid.uuid1())}


def _advertised_host(host: str) -> str:
    if host in ("", "0.0.0.0", "::"):
        return served_name()
    return host


def _bind_error(err: OSError, host: str, port: int) -> RostoolError:
    if err.errno == errno.EADDRINUSE:
        return RostoolError(
            f"port {port} is in use on {host}: another master is probably running; pick another with --port"
        )
    if err.errno == errno.EACCES:
        return RostoolError(f"no permission to listen on port {port} on {host}; pick a port above 1023")
    if isinstance(err, socket.gaierror):
        return RostoolError(f"unknown host {host!r}; give an address of this machine with --host")
    return RostoolError(f"cannot listen on {host}:{port}: {err.strerror or err}; check --host and --port")


class Master:
    """A ROS 1 master with its parameter server, served over XML-RPC on `host:port`."""

    def __init__(self, host: str = MASTER_HOST, port: int = MASTER_PORT, *, set_core_params: bool = True):
        self.host = host
        self.port = port
        self.api = MasterApi()
        self._set_core_params = set_core_params
        self._server: _Server | None = None
        self._thread: threading.Thread | None = None

    @property
    def uri(self) -> str:
        return self.api.uri

    def start(self) -> str:
        """Bind and serve in a background thread; returns the master URI (ROS_MASTER_URI)."""
        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        try:
            server = _Server((self.host, self.port), family)
        except OSError as err:
            raise _bind_error(err, self.host, self.port) from None
        self.port = int(server.server_address[1])
        host = _advertised_host(self.host)
        self.api.uri = f"http://[{host}]:{self.port}/" if ":" in host else f"http://{host}:{self.port}/"
        if self._set_core_params:
            for key, value in core_params().items():
                self.api.params.set(key, value)
        server.register_instance(self.api)
        self._server = server
        self._thread = threading.Thread(
            target=server.serve_forever, kwargs={"poll_interval": 0.1}, name="rostool core", daemon=True
        )
        self._thread.start()
        return self.uri

    def wait(self, timeout: float | None = None) -> bool:
        """Block until a shutdown is requested; False when `timeout` passed first."""
        return self.api.shutdown_requested.wait(timeout)

    def request_stop(self, reason: str = "") -> None:
        """Make wait() return (from another thread; not from a signal handler, it takes a lock)."""
        self.api.shutdown_reason = self.api.shutdown_reason or reason
        self.api.shutdown_requested.set()

    @property
    def stop_reason(self) -> str:
        return self.api.shutdown_reason

    def stop(self) -> None:
        server, self._server = self._server, None
        if server is None:
            return
        server.shutdown()
        server.server_close()
        server.close_connections()
        self.api.notifier.close()
        if self._thread is not None:
            self._thread.join()
        self.api.shutdown_requested.set()

    def __enter__(self) -> Master:
        self.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.stop()
