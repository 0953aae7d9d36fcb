"""The live-graph interface every ROS version implements; the verbs only talk to this."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol, TypedDict

if TYPE_CHECKING:
    from rostool.graph.qos import QosRequest
    from rostool.graph.recording import Encoding, RecordSource


@dataclass(frozen=True)
class NetworkCheck:
    """One of `rostool doctor`'s network checks: its name, whether it passed, what was found (one line)."""

    name: str
    ok: bool
    detail: str


@dataclass
class TopicInfo:
    """A topic as the listings show it: its type and the nodes that publish and subscribe to it."""

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


@dataclass
class ActionSummary:
    """An action as the listing verbs see it: its type and the nodes serving and calling it."""

    name: str
    type: str
    servers: list[str]
    clients: list[str]


class ActionInfo(TypedDict, total=False):
    """`action_info`'s facts (an ActionSummary's fields; ROS 1 adds the goals its status topic lists)."""

    name: str
    type: str
    servers: list[str]
    clients: list[str]
    goals: list[dict[str, Any]] | None


class EndpointQos(TypedDict):
    reliability: str | None
    durability: str | None
    depth: int | None


class TopicEndpointQos(EndpointQos, total=False):
    liveliness: str | None  # None: DDS's default (automatic)
    liveliness_lease_duration: float | None  # seconds; None: infinite


class TopicEndpoint(TypedDict):
    """One row of `topic_endpoints` (ros2 topic info -v): a publisher or subscription of the topic."""

    node: str
    endpoint_type: str  # "PUBLISHER" or "SUBSCRIPTION"
    type: str
    type_hash: str | None
    gid: str  # dotted hex
    qos: TopicEndpointQos


class ServiceEndpointFacts(TypedDict):
    gid: str
    is_writer: bool
    qos: EndpointQos


class ServiceSide(TypedDict):
    """A client or server of a service: its node, type, type hash and request/reply endpoints."""

    node: str
    endpoint_type: str  # "CLIENT" or "SERVER"
    type: str
    type_hash: str | None
    endpoints: dict[str, ServiceEndpointFacts]  # "request" and/or "reply"


class ServiceInfo(TypedDict):
    """`service_info`'s facts (ros2 service info): the service's types, clients and servers."""

    name: str
    types: list[str]
    clients: list[ServiceSide]
    servers: list[ServiceSide]


@dataclass
class GoalEvent:
    """One moment of a goal as its renderer shows it: feedback, a status change or the result; the status
    is named as the backend's ROS version names it."""

    kind: str  # "feedback", "status" or "result"
    status: int
    status_name: str
    message: Any = None  # the feedback or result message
    text: str = ""


@dataclass
class GoalOutcome:
    """How a goal ended (`send_goal`): status None when the server did not accept it."""

    goal_id: str
    status: int | None
    result: Any = None
    text: str = ""
    canceled: bool = False
    succeeded: bool = False


@dataclass
class CancelingGoal:
    """A goal the action server says it is canceling (`cancel_goals`)."""

    goal_id: str  # hex
    stamp: Any  # when the server accepted the goal (the version's time message)


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


OnMessage = Callable[[Received], None]
OnError = Callable[[str], None]


class Subscription(Protocol):
    def close(self) -> None: ...


class Publisher(Protocol):
    topic: str

    def publish(self, message: object) -> None: ...
    def wait_for_subscribers(self, count: int, timeout: float) -> bool: ...
    @property
    def subscriber_count(self) -> int: ...


class RawPublisher(Publisher, Protocol):
    """bag play's publisher: messages as bytes in the graph's `encoding`."""

    def publish_raw(self, payload: bytes) -> None: ...


class ServedService(Protocol):
    """A service this process serves (`Graph.serve_service`) until closed."""

    def close(self) -> None: ...


class ParameterDescriptor(TypedDict):
    """`Parameters.descriptor`'s facts (ros2 param describe)."""

    name: str
    type: str
    description: str
    additional_constraints: str
    read_only: bool


class Parameters(Protocol):
    """One node's parameters. `set`/`delete` return (successful, the node's reason); `show` returns the
    value and the text the style's tool prints for it; `load` returns (name, successful, reason) lines."""

    node: str

    def names(self) -> list[str]: ...
    def show(self, name: str) -> tuple[Any, str]: ...
    def set(self, name: str, value: Any) -> tuple[bool, str]: ...
    def delete(self, name: str) -> tuple[bool, str]: ...
    def descriptor(self, name: str) -> ParameterDescriptor: ...
    def dump(self) -> Any: ...
    def load(self, document: Any, use_wildcard: bool, source: str) -> list[tuple[str, bool, str]]: ...


class GoalWatcher(Protocol):
    """What a goal's progress is told to (the style's renderer)."""

    def sent(self, goal_id: str, goal: Any = None, accepted: bool = True) -> None: ...
    def event(self, event: GoalEvent) -> None: ...
    def waiting(self, text: str) -> None: ...
    def canceling(self, goal_id: str) -> None: ...


class Graph(Protocol):
    """Nodes, topics, parameters of one live graph."""

    ros_version: int
    # the ecosystem whose argument forms and output the verbs follow (rosservice's or ros2 service's text,
    # echo's secs/nsecs or sec/nanosec): renderers are chosen by it, never by the backend's class
    style: Literal["ros1", "ros2"]
    encoding: Encoding  # how messages are on the wire (bag play and record move them as bytes)
    types: Any  # the backend's type support: bag play registers and checks types with it

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
    def topic_endpoints(self, name: str) -> list[TopicEndpoint]: ...  # ros2 topic info -v's rows
    def subscribe(
        self,
        topic: str,
        on_message: Callable[[Received], None],
        on_error: Callable[[str], None] | None = None,
    ) -> Subscription: ...
    def publisher(self, topic: str, type_name: str, latch: bool = False) -> Publisher: ...
    # bag play: a publisher of bytes in `encoding` (`publish_raw`) for a type of `types`
    def raw_publisher(self, topic: str, wire_type: Any, latch: bool = False) -> RawPublisher: ...
    def record_source(self, warn: Callable[[str], None], include_hidden: bool = False) -> RecordSource: ...
    def message_class(self, type_name: str) -> type: ...
    def build_message(self, type_name: str, value: Any) -> Any: ...
    def node_uri(self, name: str) -> str: ...
    def use_qos(self, qos: QosRequest) -> None: ...

    # services: `services()` gives (name, type or None where only the server knows it, server nodes)
    def services(self) -> list[tuple[str, str | None, list[str]]]: ...
    def service_type(self, name: str) -> str: ...
    def service_uri(self, name: str) -> str: ...
    def service_nodes(self, name: str) -> list[str]: ...
    def service_args(self, name: str) -> str: ...
    def service_info(self, name: str) -> ServiceInfo | None: ...  # what the style's info prints
    def find_services(self, type_name: str) -> list[str]: ...
    # serve NAME of `pkg/srv/Type` from this process's node: handler(request) -> the response's fields
    def serve_service(
        self, name: str, srv_type: str, handler: Callable[[Any], Mapping[str, Any]]
    ) -> ServedService: ...
    # call with the command-line values (in the style's forms): (request, response)
    def service_call(
        self, name: str, values: tuple[str, ...], wait: bool, timeout: float | None
    ) -> tuple[Any, Any]: ...

    # actions: summaries have name, type, servers, clients
    def actions(self) -> list[ActionSummary]: ...
    def action_info(self, name: str, wait: float) -> ActionInfo: ...
    # follow a goal to its result (canceled first on timeout or Ctrl+C)
    def send_goal(
        self, name: str, kind: str | None, goal: Any, timeout: float | None, w: GoalWatcher
    ) -> GoalOutcome: ...
    # cancel one goal or all: the goals the server says it is canceling (where it says so)
    def cancel_goals(self, name: str, goal_id: str | None) -> list[CancelingGoal]: ...

    # parameters: per node (ROS 1: NODE, when given, is a namespace of the one parameter server)
    def parameters(self, node: str | None, timeout: float = 5.0) -> Parameters: ...
