"""ROS 2 services through rclpy: rmw lists them and rclpy's generic client calls them.

The request is built from the command line's YAML in rosbags' store, exactly as the DDS backend builds it,
then turned into the class rclpy imports through its CDR bytes (and the response back the same way), so
`service call` prints what it prints with the DDS backend. The types come from rosbags' store, rostool's
built-in definitions or .srv sources where the DDS backend finds them, else from the imported class.
"""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.rclpy import types as rtypes
from rostool.graph.rclpy.host import type_hash
from rostool.graph.ros2_base.calls import ReplyWait, ServiceTimeout
from rostool.graph.ros2_base.names import reply_topic, request_topic, resolve, service_type
from rostool.graph.ros2_base.transport import ServiceEndpoint

if TYPE_CHECKING:
    from rostool.graph.rclpy.host import RclpyHost

_GONE_CHECK = 1.0  # a call without a reply checks this often that its server is still there


def service_store_names(graph: RclpyHost, srv_type: str) -> tuple[str, str, str]:
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


class RclpyServiceClient(ReplyWait):
    """Calls one service through an rclpy client; requests and replies are rosbags messages."""

    def __init__(self, graph: RclpyHost, service: str, srv_type: str) -> None:
        super().__init__()
        self._graph = graph
        self.service = resolve(service)
        self.srv_type, self.request_type, self.response_type = service_store_names(graph, srv_type)
        self._cls = rtypes.python_class(self.srv_type)
        self._client = graph.node.create_client(self._cls, self.service)

    def wait_for_server(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while not self._client.service_is_ready():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

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
                    raise ServiceTimeout(
                        f"service {self.service} did not reply within {timeout:g} s; "
                        "give a longer --timeout if the service is slow"
                    )
                if now >= next_check:
                    next_check = now + _GONE_CHECK
                    if not self._client.service_is_ready():
                        raise self._gone()
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


class RclpyServiceServer:
    """Serves one service through an rclpy service: `answer(request) -> response`, rosbags messages both,
    called on the executor's thread. The class rclpy imports must exist (else one line naming the package)."""

    def __init__(self, graph: RclpyHost, service: str, srv_type: str, answer: Any) -> None:
        self._graph = graph
        self.service = resolve(service)
        self.srv_type, self.request_type, self.response_type = service_store_names(graph, srv_type)
        self._cls = rtypes.python_class(self.srv_type)
        self._answer = answer
        self._server = graph.node.create_service(self._cls, self.service, self._serve)

    def _serve(self, request: Any, _response: Any) -> Any:
        types = self._graph.types
        reply = self._answer(rtypes.from_rclpy(types, request, self.request_type))
        return rtypes.to_rclpy(types, reply, self.response_type, self._cls.Response)

    def close(self) -> None:
        try:
            self._graph.node.destroy_service(self._server)
        except Exception:  # the context is already shut down: rclpy destroyed it
            return


def service_endpoints(graph: RclpyHost) -> list[tuple[str, str, list[str], list[str]]]:
    """(name, type, server nodes, client nodes) of every service that has a server, node by node."""
    graph.settle(require_peers=True)
    node = graph.node
    found: dict[str, tuple[str, set[str], set[str]]] = {}
    for name, namespace in graph.node_pairs():
        full = graph.full_name(name, namespace)
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


def service_endpoint_views(graph: RclpyHost, resolved: str) -> list[ServiceEndpoint]:
    """The service's endpoints from rmw's view of its two DDS topics (`rq/<name>Request`,
    `rr/<name>Reply`), which carry node, GID, QoS and type hash."""
    from rostool.graph.rclpy.qos import from_rclpy

    node, own = graph.node, graph.own_node
    endpoints: list[ServiceEndpoint] = []
    for kind, topic in (("request", request_topic(resolved)), ("reply", reply_topic(resolved))):
        writers = node.get_publishers_info_by_topic(topic, no_mangle=True)
        readers = node.get_subscriptions_info_by_topic(topic, no_mangle=True)
        for is_writer, infos in ((True, writers), (False, readers)):
            endpoints += [
                ServiceEndpoint(
                    kind=kind, node=graph.full_name(info.node_name, info.node_namespace),
                    is_writer=is_writer, service_type=_service_type_of(info.topic_type),
                    type_hash=type_hash(info), gid=bytes(info.endpoint_gid).hex("."),
                    qos=vars(from_rclpy(info.qos_profile)),
                )
                for info in infos
                if info.node_name != own
            ]  # fmt: skip
    return endpoints


def _service_type_of(topic_type: str) -> str:
    """`pkg/srv/Name` of a request or reply topic's type, as rmw names it (`pkg::srv::dds_::Name_Request_`
    when not demangled, `pkg/srv/Name_Request` when it is)."""
    if "::" in topic_type:
        parts = [p for p in topic_type.split("::") if p != "dds_"]
        topic_type = "/".join(parts).removesuffix("_")
    return service_type(topic_type)
