"""ROS 2 services through rclpy: rmw lists them and rclpy's generic client calls them.

The request is built from the command line's YAML in rosbags' store, exactly as the DDS backend builds it,
then turned into the class rclpy imports through its CDR bytes (and the response back the same way), so
`service call` prints what it prints with the DDS backend. The types come from rosbags' store, rostool's
built-in definitions or .srv sources where the DDS backend finds them, else from the imported class.
"""

from __future__ import annotations

import math
import threading
import time
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.rclpy import types as rtypes
from rostool.graph.ros2.names import reply_topic, request_topic, resolve, service_type

if TYPE_CHECKING:
    from rostool.graph.rclpy.graph import RclpyGraph

DEFAULT_REPLY_TIMEOUT = 30.0  # as the DDS backend: a call given no timeout still ends after this long
_GONE_CHECK = 1.0  # a call without a reply checks this often that its server is still there


def service_store_names(graph: RclpyGraph, srv_type: str) -> tuple[str, str, str]:
    """(`pkg/srv/Name`, its request and response names in rosbags' store) for `pkg/Name` or `pkg/srv/Name`
    (`pkg/action/X_SendGoal` too); the rclpy class must import."""
    from rostool.interfaces.ros2_srv import register_service

    parts = srv_type.strip().strip("/").split("/")
    if len(parts) == 2:
        parts.insert(1, "srv")
    if len(parts) != 3 or parts[1] not in ("srv", "action") or not all(parts):
        raise RostoolError(f"bad service type {srv_type!r}: use pkg/srv/Name (or pkg/Name)")
    full = "/".join(parts)
    rtypes.python_class(full)  # one line naming the package when rclpy cannot import it
    try:
        request, response = register_service(graph.types, full)
    except RostoolError:  # neither built in nor in a source file: described from the class
        request, response = f"{full}_Request", f"{full}_Response"
        for name in (request, response):
            rtypes.ensure_known(graph.types, name)
    return full, request, response


class RclpyServiceClient:
    """Calls one service through an rclpy client; requests and replies are rosbags messages."""

    def __init__(self, graph: RclpyGraph, service: str, srv_type: str) -> None:
        self._graph = graph
        self.service = resolve(service)
        self.srv_type, self.request_type, self.response_type = service_store_names(graph, srv_type)
        self._cls = rtypes.python_class(self.srv_type)
        self._client = graph.node.create_client(self._cls, self.service)
        self._lock = threading.Lock()

    def wait_for_server(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while not self._client.service_is_ready():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    def call(self, request: object, timeout: float = 5.0, forever: bool = False) -> Any:
        """The server's reply to `request` (a rosbags message), as the DDS backend's client answers."""
        if math.isinf(timeout) and not forever:
            timeout = DEFAULT_REPLY_TIMEOUT
        started = time.monotonic()
        if not self.wait_for_server(min(timeout, DEFAULT_REPLY_TIMEOUT)):
            raise RostoolError(
                f"service {self.service} is not available: no server matched within "
                f"{min(timeout, DEFAULT_REPLY_TIMEOUT):g} s (see `rostool service list`; --wait waits longer)"
            )
        with self._lock:
            return self._exchange(request, started + timeout, timeout)

    def _exchange(self, request: object, deadline: float, timeout: float) -> Any:
        types = self._graph.types
        message = rtypes.to_rclpy(types, request, self.request_type, self._cls.Request)
        future = self._client.call_async(message)
        done = threading.Event()
        future.add_done_callback(lambda _f: done.set())
        next_check = time.monotonic() + _GONE_CHECK
        try:
            while not done.wait(0.02):
                now = time.monotonic()
                if now >= deadline:
                    from rostool.graph.ros2.services import ServiceTimeout

                    raise ServiceTimeout(
                        f"service {self.service} did not reply within {timeout:g} s; "
                        "give a longer --timeout if the service is slow"
                    )
                if now >= next_check:
                    next_check = now + _GONE_CHECK
                    if not self._client.service_is_ready():
                        raise RostoolError(
                            f"the server of {self.service} went away before it replied (see `rostool "
                            "service list`); call again when it is back"
                        )
        except BaseException:
            self._client.remove_pending_request(future)
            raise
        if future.exception() is not None:
            raise RostoolError(f"calling {self.service} failed: {' '.join(str(future.exception()).split())}")
        return rtypes.from_rclpy(types, future.result(), self.response_type)

    def close(self) -> None:
        try:
            self._graph.node.destroy_client(self._client)
        except Exception:  # the context is already shut down: rclpy destroyed it
            return


class ServiceVerbs:
    """The Graph protocol's services on RclpyGraph."""

    def services(self: RclpyGraph) -> list[tuple[str, str | None, list[str]]]:
        """(name, type, server nodes) of every service another node serves."""
        return [(name, type_, servers) for name, type_, servers, _clients in self.service_endpoints()]

    def service_endpoints(self: RclpyGraph) -> list[tuple[str, str, list[str], list[str]]]:
        """(name, type, server nodes, client nodes) of every service that has a server."""
        self.settle(require_peers=True)
        node = self.node
        found: dict[str, tuple[str, set[str], set[str]]] = {}
        for name, namespace in self._node_pairs():
            full = self._full_name(name, namespace)
            try:
                servers = node.get_service_names_and_types_by_node(name, namespace)
                clients = node.get_client_names_and_types_by_node(name, namespace)
            except Exception:  # NodeNameNonExistentError: the node left in the meantime
                continue
            for service, types in servers:
                entry = found.setdefault(service, (types[0] if types else "", set(), set()))
                found[service] = (types[0] if types else entry[0], entry[1] | {full}, entry[2])
            for service, _types in clients:
                entry = found.setdefault(service, ("", set(), set()))
                entry[2].add(full)
        return [
            (name, type_, sorted(servers), sorted(clients))
            for name, (type_, servers, clients) in sorted(found.items())
            if servers
        ]

    def find_service_type(self: RclpyGraph, service: str) -> str | None:
        resolved = resolve(service)
        return next((type_ for name, type_, _nodes in self.services() if name == resolved), None)

    def service_type(self: RclpyGraph, name: str) -> str:
        found = self.find_service_type(name)
        if found is None:
            raise RostoolError(f"unknown service {self.resolve(name)}: no server announces it")
        return found

    def find_services(self: RclpyGraph, type_name: str) -> list[str]:
        from rostool.interfaces.names import hidden_name

        pkg, _, name = type_name.strip().strip("/").rpartition("/")
        wanted = f"{pkg.removesuffix('/srv')}/srv/{name}"
        return [s for s, type_, _nodes in self.services() if type_ == wanted and not hidden_name(s)]

    def service_client(self: RclpyGraph, service: str, srv_type: str) -> RclpyServiceClient:
        return RclpyServiceClient(self, service, srv_type)

    def service_call(
        self: RclpyGraph, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
    ) -> tuple[Any, Any]:
        """ros2 service call, as the DDS backend does it (its steps and its lines)."""
        from rostool.graph.ros2_calls import call_service

        return call_service(self, name, values, wait, timeout)

    def service_info(self: RclpyGraph, service: str) -> dict[str, Any] | None:
        """ros2 service info's facts, as the DDS backend gives them: from rmw's view of the service's two
        DDS topics (`rq/<name>Request`, `rr/<name>Reply`), which carry node, GID, QoS and type hash."""
        from rostool.graph.rclpy.graph import _type_hash
        from rostool.graph.rclpy.qos import from_rclpy
        from rostool.graph.ros2_calls import ServiceEndpoint, service_info_facts

        resolved = resolve(service)
        self.settle(require_peers=True)
        node, own = self.node, self._node_name
        endpoints: list[ServiceEndpoint] = []
        for kind, topic in (("request", request_topic(resolved)), ("reply", reply_topic(resolved))):
            writers = node.get_publishers_info_by_topic(topic, no_mangle=True)
            readers = node.get_subscriptions_info_by_topic(topic, no_mangle=True)
            for is_writer, infos in ((True, writers), (False, readers)):
                endpoints += [
                    ServiceEndpoint(
                        kind=kind, node=self._full_name(info.node_name, info.node_namespace),
                        is_writer=is_writer, service_type=_service_type_of(info.topic_type),
                        type_hash=_type_hash(info), gid=bytes(info.endpoint_gid).hex("."),
                        qos=vars(from_rclpy(info.qos_profile)),
                    )
                    for info in infos
                    if info.node_name != own
                ]  # fmt: skip
        return service_info_facts(resolved, endpoints)


def _service_type_of(topic_type: str) -> str:
    """`pkg/srv/Name` of a request or reply topic's type, as rmw names it (`pkg::srv::dds_::Name_Request_`
    when not demangled, `pkg/srv/Name_Request` when it is)."""
    if "::" in topic_type:
        parts = [p for p in topic_type.split("::") if p != "dds_"]
        topic_type = "/".join(parts).removesuffix("_")
    return service_type(topic_type)
