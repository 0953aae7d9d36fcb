"""The live graph: which ROS version to talk to, and the backend that implements it."""

from __future__ import annotations

import os
import socket
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from rostool.graph.ros1.env import MASTER_HOST as MASTER_HOST  # `rostool core`
from rostool.graph.ros1.env import MASTER_PORT

if TYPE_CHECKING:
    from rostool.graph.base import Graph
    from rostool.graph.daemon.client import DaemonClient
    from rostool.graph.ros1.master import Master


def select_ros_version(explicit: int | None) -> int:
    """--ros1/--ros2, else ROS_VERSION, else ROS 1 when a master is configured or answers, else ROS 2."""
    if explicit in (1, 2):
        return explicit
    env_version = os.environ.get("ROS_VERSION", "").strip()
    if env_version in ("1", "2"):
        return int(env_version)
    if os.environ.get("ROS_MASTER_URI"):
        return 1
    if _port_answers("127.0.0.1", MASTER_PORT):
        return 1
    return 2


def _port_answers(host: str, port: int, timeout: float = 0.2) -> bool:
    try:
        with socket.create_connection((host, port), timeout=timeout):
            return True
    except OSError:
        return False


def open_graph(
    explicit_version: int | None,
    node_name: str = "rostool",
    interface_paths: Sequence[str] = (),
    ros2_backend: str | None = None,
    use_daemon: bool = True,
    spin_time: float | None = None,
) -> Graph:
    """Connect to the live graph of the selected ROS version. Types missing from the built-in ones are looked
    for in `interface_paths` (default: ROSTOOL_INTERFACES), ROS_PACKAGE_PATH and the workspace. ROS 2 goes
    through rclpy or rostool's DDS as `ros2_backend` (default: ROSTOOL_ROS2_BACKEND, else auto) chooses,
    and through the user's graph daemon unless `use_daemon` is false or ROSTOOL_NO_DAEMON=1; when it
    answers directly, its listings wait `spin_time` seconds for discovery (None: until it settles)."""
    from rostool.interfaces.sources import interface_paths_from_env

    version = select_ros_version(explicit_version)
    interface_paths = tuple(interface_paths) or interface_paths_from_env()
    if version == 2:

        def direct() -> Graph:
            from rostool.graph.backends import open_ros2

            return open_ros2(ros2_backend, node_name, interface_paths, spin_time)[1]

        if not (use_daemon and daemon_allowed()):
            return direct()
        from rostool.graph.daemon.graph import daemon_graph

        return daemon_graph(ros2_backend, direct, wait_for_starting=spin_time is None)
    from rostool.graph.ros1.graph import Ros1Graph

    return Ros1Graph(node_name, interface_paths)


def daemon_allowed() -> bool:
    """Whether ROS 2 graph queries may go through the user's graph daemon: not with ROSTOOL_NO_DAEMON=1."""
    from rostool.graph.daemon import NO_DAEMON_ENV

    return os.environ.get(NO_DAEMON_ENV, "").strip() in ("", "0")


def daemon_client(ros2_backend: str | None) -> DaemonClient:
    """The client of the user's graph daemon for the backend asked for (`rostool daemon` verbs)."""
    from rostool.graph.daemon.client import DaemonClient
    from rostool.graph.rclpy.select import requested

    return DaemonClient(requested(ros2_backend)[0])


def every_daemon_client() -> list[DaemonClient]:
    """Clients of every graph daemon of this user (all domains and keys): `rostool daemon stop --all`."""
    from rostool.graph.daemon.client import every_daemon

    return every_daemon()


def embedded_master(host: str, port: int) -> Master:
    """A ROS 1 master and parameter server run inside rostool (`rostool core`)."""
    from rostool.graph.ros1.master import Master

    return Master(host, port)


def network_checks(version: int, listen: float | None = None) -> tuple[dict[str, Any], list[Any]]:
    """`rostool doctor`'s network facts and checks (each with .name, .ok, .detail) for one ROS version."""
    if version == 1:
        from rostool.graph.ros1 import doctor as ros1_doctor

        return {}, list(ros1_doctor.checks())
    from rostool.graph.ros2_base import doctor as ros2_doctor

    facts, found = ros2_doctor.checks(os.environ, ros2_doctor.LISTEN_SECONDS if listen is None else listen)
    return facts, list(found)


def ros2_report(ros2_backend: str | None) -> dict[str, Any]:
    """What `rostool doctor` says of ROS 2: the backend chosen and why, rclpy, RMW, distro, discovery."""
    from rostool.graph.rclpy import facts
    from rostool.graph.rclpy.select import choose

    return facts.report(choose(ros2_backend))
