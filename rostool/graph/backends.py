"""The one place that opens a ROS 2 backend: rclpy (the user's client library and RMW) or rostool's own
DDS, as `rclpy/select.py` chooses. Verbs reach it through `open_graph()`, the graph daemon directly."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rostool.graph.ros2_base.graph import Ros2Base


def open_ros2(
    backend: str | None,
    node_name: str = "rostool",
    interface_paths: Sequence[str] = (),
    spin_time: float | None = None,
) -> tuple[str, Ros2Base]:
    """(the backend chosen: "rclpy" or "dds", its graph) for `backend` (auto|rclpy|dds; None: the
    environment's choice); its listings wait `spin_time` seconds for discovery (None: until it settles)."""
    from rostool.graph.rclpy.select import choose

    chosen = choose(backend).backend
    graph: Ros2Base
    if chosen == "rclpy":
        from rostool.graph.rclpy.graph import RclpyGraph

        graph = RclpyGraph(node_name, interface_paths=interface_paths)
    else:
        from rostool.graph.ros2.discovery import start_discovery

        discovery = start_discovery()  # first: discovery runs while the rest is imported and built
        from rostool.graph.ros2.graph import Ros2Graph

        graph = Ros2Graph(node_name, interface_paths=interface_paths, discovery=discovery)
    graph.spin_time = spin_time  # type: ignore[attr-defined]
    return chosen, graph
