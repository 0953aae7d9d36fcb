"""ROS 2 parameters through rclpy: the DDS backend's parameter client (its requests, values, files and
lines) with its rcl_interfaces service calls made by rclpy's generic clients."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.ros2 import params
from rostool.graph.ros2.protocol import NodeParameters

if TYPE_CHECKING:
    from rostool.graph.rclpy.graph import RclpyGraph


class RclpyParameters(NodeParameters):
    _graph: RclpyGraph

    def _call(self, verb: str, request: dict[str, Any]) -> Any:
        from rostool.interfaces.fill import build_message

        client = self._clients.get(verb)
        if client is None:
            if not self._clients:
                self._check_node()
            srv_type = "rcl_interfaces/srv/" + "".join(w.capitalize() for w in verb.split("_"))
            client = self._clients[verb] = self._graph.service_client(f"{self.node}/{verb}", srv_type)
        if not client.wait_for_server(self._timeout):
            raise RostoolError(
                f"node {self.node} does not serve {verb}: no server of {client.service} matched within "
                f"{self._timeout:g} s (see `rostool service list`)"
            )
        store = self._graph.types.store
        return client.call(build_message(store, client.request_type, request), self._timeout)

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
