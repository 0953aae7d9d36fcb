"""What the rclpy backend does not do yet: one line each, naming the DDS backend, which does it."""

from __future__ import annotations

from rostool.errors import RostoolError


def not_yet(what: str) -> RostoolError:
    return RostoolError(f"{what} is not available with the rclpy backend yet; use --ros2-backend dds")


def ros1_only(what: str) -> RostoolError:
    from rostool.graph.ros2.protocol import ros1_only as dds_line  # the DDS backend's line

    return dds_line(what)


class NotYet:
    def ping(self, name: str) -> float:
        raise RostoolError("ROS 2 nodes cannot be pinged (there is no node API); try `rostool node info`")

    def kill(self, name: str) -> None:
        raise RostoolError("ROS 2 nodes cannot be killed remotely (there is no node API); stop the process")

    def service_uri(self, name: str) -> str:
        raise ros1_only("service uri")

    def service_nodes(self, name: str) -> list[str]:
        raise ros1_only("service node (on ROS 2: service list -n)")

    def service_args(self, name: str) -> str:
        raise ros1_only("service args")
