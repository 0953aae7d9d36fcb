"""What a ROS 2 transport gives the shared graph: endpoints as it sees them, writers that take CDR bytes,
service clients. The DDS backend (rostool's own participant) and the rclpy backend (the user's RMW) each
provide these; everything built on them is written once in this package."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from rostool.graph.base import Graph

if TYPE_CHECKING:
    from rostool.graph.ros2_base.qos import QosProfile, QosRequest
    from rostool.interfaces.ros2_types import Ros2Types


@dataclass(frozen=True)
class EndpointView:
    """One reader or writer of a ROS 2 topic in another process, as the transport describes it."""

    node: str  # its node's full name (UNKNOWN_NODE when no node claims it)
    is_writer: bool
    type_name: str  # pkg/msg/Name
    type_hash: str | None  # RIHS01_... as announced ("" or None when not)
    gid: str  # dotted hex
    qos: QosProfile


@dataclass(frozen=True)
class ServiceEndpoint:
    """One DDS endpoint of a service as a transport sees it: a request or reply writer or reader."""

    kind: str  # "request" or "reply"
    node: str
    is_writer: bool
    service_type: str  # pkg/srv/Name
    type_hash: str | None
    gid: str
    qos: dict[str, Any]


class Writer(Protocol):
    """A transport's writer of one topic: CDR bytes (with their encapsulation header) out as they are."""

    def write(self, payload: bytes) -> None: ...

    def matched(self) -> int: ...


class ServiceClient(Protocol):
    """A transport's client of one service: requests and replies are rosbags messages."""

    service: str
    request_type: str

    def wait_for_server(self, timeout: float) -> bool: ...

    def call(self, request: object, timeout: float = 5.0, forever: bool = False) -> Any: ...

    def close(self) -> None: ...


class Ros2Host(Graph, Protocol):
    """What the shared pieces (subscriptions, recording, parameters, calls, actions) ask of a ROS 2 graph
    beyond the Graph protocol: the transport's view of endpoints and services."""

    types: Ros2Types
    qos_request: QosRequest
    warn: Callable[[str], None]

    def service_endpoints(self, nodes: bool = False) -> list[tuple[str, str, list[str], list[str]]]: ...

    def find_service_type(self, service: str) -> str | None: ...

    def service_client(self, service: str, srv_type: str) -> ServiceClient: ...

    def topic_views(self, topic: str) -> list[EndpointView]: ...

    def _all_topic_views(self) -> Iterable[tuple[str, EndpointView]]:
        """(topic, endpoint) of every remote endpoint as the transport knows it now, without waiting."""
        ...

    def wait_for_newcomers(self, limit: float = 1.0) -> None: ...

    def published_topics(self) -> set[str]: ...

    def before_node_check(self) -> None: ...

    def serves_under(self, prefix: str) -> bool: ...

    def announces_node(self, node: str) -> bool: ...
