"""What ROS 2 has no way to do (ping and kill a node) or only ROS 1 has (service uri/node/args): the DDS
backend's lines."""

from __future__ import annotations

from rostool.errors import RostoolError


def ros1_only(what: str) -> RostoolError:
    from rostool.graph.ros2.protocol import ros1_only as dds_line  # the DDS backend's line

    return dds_line(what)


class Refusals:
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
