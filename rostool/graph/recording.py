"""Where `bag record` gets messages: every backend's `Graph.record_source()` (ROS 1: TCPROS bytes,
ROS 2: CDR bytes over DDS).

A source finds published topics, subscribes with a callback `put(topic, payload, origin)` called from
network threads, and describes an origin once (the connection header a bag stores). `origin` is whatever
identifies one publisher connection cheaply: a TCPROS link in ROS 1, the topic's type name in ROS 2.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal, Protocol, runtime_checkable

from rostool.errors import RostoolError

Encoding = Literal["ros1", "cdr"]
Put = Callable[[str, bytes, Any], None]


class RecordSource(Protocol):
    encoding: Encoding
    types: Any  # ROS 1: the graph's TypeRegistry
    store: Any  # ROS 2: the graph's rosbags type store

    def resolve(self, name: str) -> str: ...

    def published_topics(self) -> list[str]: ...

    def topics_present(self) -> list[str]:
        """The topics published at start-up, once the graph is known (--no-discovery's fixed list)."""
        ...

    def subscribed_topics(self, node: str) -> list[str]: ...

    def subscribe(self, topic: str, put: Put) -> None: ...

    def describe(self, topic: str, origin: Any) -> dict[str, str]: ...

    def close(self) -> None: ...


@runtime_checkable
class TypedRecordSource(RecordSource, Protocol):
    """A source that subscribes with a type given up front, before any publisher shows it (ROS 2:
    `ros2 bag record --static-topics-path`); ROS 1 learns a topic's type from its publishers only."""

    def known_type(self, type_name: str) -> str:
        """The type's name as `describe` and the bag give it; RostoolError when the types cannot say."""
        ...

    def subscribe(self, topic: str, put: Put, type_name: str | None = None) -> None: ...


class _Topic(Protocol):
    name: str
    subscribers: list[str]


class TopicLister(Protocol):
    """What `subscribed_by` asks of a graph (a Graph is one)."""

    def topics(self) -> Sequence[_Topic]: ...


def subscribed_by(graph: TopicLister, node: str) -> list[str]:
    """The topics `node` subscribes to now; none while the graph does not answer."""
    try:
        return [t.name for t in graph.topics() if node in t.subscribers]
    except RostoolError:
        return []
