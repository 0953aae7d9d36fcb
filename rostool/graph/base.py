"""The live-graph interface every ROS version implements; the verbs only talk to this."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol


@dataclass
class TopicInfo:
    name: str
    type: str
    publishers: list[str] = field(default_factory=list)
    subscribers: list[str] = field(default_factory=list)


@dataclass
class Connection:
    topic: str
    peer: str
    direction: str  # "inbound" or "outbound"
    transport: str


@dataclass
class NodeInfo:
    name: str
    uri: str
    pid: int | None
    publications: list[tuple[str, str]]
    subscriptions: list[tuple[str, str]]
    services: list[str]
    connections: list[Connection]
    # ROS 2: service name -> type for `services`, and the services the node calls (name, type)
    service_types: dict[str, str] = field(default_factory=dict)
    service_clients: list[tuple[str, str]] = field(default_factory=list)


class Received:
    """One message as it arrived: raw bytes plus the decoder of its connection, used on demand."""

    __slots__ = ("decoder", "payload", "recv_time_ns", "topic", "type_name")

    def __init__(
        self, topic: str, payload: bytes, recv_time_ns: int, type_name: str, decoder: Callable[[bytes], Any]
    ) -> None:
        self.topic = topic
        self.payload = payload
        self.recv_time_ns = recv_time_ns
        self.type_name = type_name
        self.decoder = decoder

    def decode(self) -> Any:
        return self.decoder(self.payload)


class Subscription(Protocol):
    def close(self) -> None: ...


class Publisher(Protocol):
    topic: str

    def publish(self, message: object) -> None: ...
    def wait_for_subscribers(self, count: int, timeout: float) -> bool: ...
    @property
    def subscriber_count(self) -> int: ...


class Graph(Protocol):
    """Nodes, topics, parameters of one live graph."""

    ros_version: int
    time_style: Literal["ros1", "ros2"]  # how echo prints times (secs/nsecs or sec/nanosec)

    def close(self) -> None: ...
    def resolve(self, name: str) -> str: ...

    # nodes
    def node_names(self) -> list[str]: ...
    def node_info(self, name: str) -> NodeInfo: ...
    def ping(self, name: str) -> float: ...
    def kill(self, name: str) -> None: ...

    # topics
    def topics(self) -> list[TopicInfo]: ...
    def topic_type(self, name: str) -> str | None: ...
    def subscribe(
        self,
        topic: str,
        on_message: Callable[[Received], None],
        on_error: Callable[[str], None] | None = None,
    ) -> Subscription: ...
    def publisher(self, topic: str, type_name: str, latch: bool = False) -> Publisher: ...
    def message_class(self, type_name: str) -> type: ...
    def build_message(self, type_name: str, value: Any) -> Any: ...
    def node_uri(self, name: str) -> str: ...

    # parameters
    def param_names(self) -> list[str]: ...
    def get_param(self, name: str) -> Any: ...
    def set_param(self, name: str, value: Any) -> None: ...
    def delete_param(self, name: str) -> None: ...
    def has_param(self, name: str) -> bool: ...
