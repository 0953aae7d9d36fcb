"""A subscription with its own QoS request and warnings, whatever its graph's: what a graph daemon opens for
each client it relays a topic to (graph/daemon/relay_server.py), each with the QoS its verb asked for."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from rostool.graph.ros2_base.names import resolve

if TYPE_CHECKING:
    from rostool.graph.base import OnError, OnMessage, Subscription
    from rostool.graph.ros2_base.graph import Ros2Base
    from rostool.graph.ros2_base.qos import QosRequest


def subscribe_for(
    graph: Ros2Base, topic: str, request: QosRequest, warn: Callable[[str], None], on_message: OnMessage,
    on_error: OnError,
) -> Subscription:  # fmt: skip
    """A subscription of `graph` that reads with `request` and warns through `warn`; the caller closes it
    (the graph does not keep it)."""
    graph._start()
    return graph._subscription(resolve(topic), on_message, on_error, request, warn)
