"""The one place that opens a ROS 2 backend: rclpy (the user's client library and RMW) or rostool's own
DDS, as `rclpy/select.py` chooses. Verbs reach it through `open_graph()`, the graph daemon directly."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rostool.graph.ros2_base.graph import Ros2Base


def open_ros2(
    backend: str | None, node_name: str = "rostool", interface_paths: Sequence[str] = ()
) -> tuple[str, Ros2Base]:
    """(the backend chosen: "rclpy" or "dds", its graph) for `backend` (auto|rclpy|dds; None: the
    environment's choice)."""
    from rostool.graph.rclpy.select import choose

    chosen = choose(backend).backend
    if chosen == "rclpy":
        from rostool.graph.rclpy.graph import RclpyGraph

        return chosen, RclpyGraph(node_name, interface_paths=interface_paths)
    from rostool.graph.ros2.graph import Ros2Graph

    return chosen, Ros2Graph(node_name, interface_paths=interface_paths)
