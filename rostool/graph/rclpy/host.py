"""What the rclpy transport's parts (services, subscriptions, actions) ask of its graph, and how they
read rmw's endpoint descriptions."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from rostool.graph.ros2_base.transport import Ros2Host

if TYPE_CHECKING:
    from rostool.graph.rclpy.context import RclpyContext


class RclpyHost(Ros2Host, Protocol):
    @property
    def context(self) -> RclpyContext: ...

    @property
    def node(self) -> Any: ...

    @property
    def own_node(self) -> str: ...

    def settle(self, require_peers: bool = False) -> bool: ...

    def node_pairs(self) -> list[tuple[str, str]]: ...

    def full_name(self, name: str, namespace: str) -> str: ...

    def store_name(self, type_name: str) -> str: ...


def type_hash(info: Any) -> str | None:
    """The RIHS01 hash of an rmw TopicEndpointInfo, None where rmw gives none (a zero hash)."""
    text = str(getattr(info, "topic_type_hash", "") or "")
    return text if text.startswith("RIHS01_") and text[7:].strip("0") else None
