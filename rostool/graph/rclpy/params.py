"""ROS 2 parameters through rclpy: the DDS backend's parameter client (its requests, values, files and
lines) with its rcl_interfaces service calls made by rclpy's generic clients."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from rostool.errors import RostoolError
from rostool.graph.ros2 import params
from rostool.graph.ros2.protocol import NodeParameters

if TYPE_CHECKING:
    from rostool.graph.rclpy.graph import RclpyGraph


class RclpyParameters(NodeParameters):
    _graph: RclpyGraph

    def _check_node(self) -> None:
        """Fail at once, after discovery settles, when the node serves no `<node>/...` service (the DDS
        backend's lines)."""
        graph = self._graph
        graph.settle()
        prefix = self.node + "/"
        deadline = time.monotonic() + params.NODE_SETTLE_SECONDS
        while True:
            served = graph.node.get_service_names_and_types()
            if any(name.startswith(prefix) for name, _types in served):
                return
            if time.monotonic() >= deadline:
                break
            time.sleep(0.05)
        nodes = {graph._full_name(n, ns) for n, ns in graph._node_pairs()}
        if self.node in nodes:
            raise RostoolError(f"node {self.node} serves no parameter services (it was started without them)")
        raise RostoolError(
            f"unknown node {self.node}: no ROS 2 participant serves its parameter services "
            "(see `rostool node list`)"
        )
