"""What `rostool doctor` reports about the ROS 2 side: the backend chosen and why, the RMW, the distro,
the domain and the discovery range, each with where it came from."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.rclpy.select import Choice

# rmw_fastrtps_cpp is the default RMW of every distro rostool knows
DEFAULT_RMW = "rmw_fastrtps_cpp"
MIDDLEWARE_VARIABLES = (
    "FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE", "RMW_FASTRTPS_USE_QOS_FROM_XML",
    "CYCLONEDDS_URI", "ROS_STATIC_PEERS",
)  # fmt: skip


def rclpy_distro(env: Mapping[str, str] = os.environ) -> tuple[str | None, str]:
    """(distro, where it was found): ROS_DISTRO, a pip-installed ros-<distro>-rclpy, or /opt/ros/<distro>."""
    from importlib import metadata

    from rostool.interfaces.typestores import DISTROS

    named = env.get("ROS_DISTRO", "").strip().lower()
    if named:
        return named, "ROS_DISTRO"
    for distro in DISTROS:
        try:
            version = metadata.version(f"ros-{distro}-rclpy")
        except metadata.PackageNotFoundError:
            continue
        return distro, f"ros-{distro}-rclpy {version} is installed"
    from importlib.util import find_spec

    spec = find_spec("rclpy")
    parts = (spec.origin or "").split(os.sep) if spec is not None else []
    if "ros" in parts and parts.index("ros") + 1 < len(parts):
        return parts[parts.index("ros") + 1], "the path of rclpy"
    return None, "not found: set ROS_DISTRO"


def rclpy_range(env: Mapping[str, str] = os.environ) -> tuple[str, str]:
    """The discovery range as rmw reads it (ROS 2's default is SUBNET); a value rmw does not know is shown
    as given: rmw itself says what is wrong with it."""
    from rostool.graph.ros2_base.env import discovery_range_reason

    try:
        return discovery_range_reason(env)
    except RostoolError:
        return env["ROS_AUTOMATIC_DISCOVERY_RANGE"].strip().upper(), "ROS_AUTOMATIC_DISCOVERY_RANGE"


def report(choice: Choice, env: Mapping[str, str] = os.environ) -> dict[str, Any]:
    """The facts for one ROS 2 backend choice, as `doctor --json` prints them."""
    from rostool.graph.ros2_base import env as ros2_env

    facts: dict[str, Any] = {
        "backend": choice.backend, "asked": choice.asked, "asked_by": choice.source, "reason": choice.reason,
    }  # fmt: skip
    try:
        facts["domain_id"] = ros2_env.domain_id(env)
        facts["domain_id_from"] = "ROS_DOMAIN_ID" if env.get("ROS_DOMAIN_ID", "").strip() else "default"
    except Exception as err:
        facts["domain_id"], facts["domain_id_from"] = None, str(err)
    if choice.backend == "rclpy":
        facts.update(_rclpy_facts(env))
    else:
        facts.update(_dds_facts(env))
    facts["middleware_settings"] = {k: env[k] for k in MIDDLEWARE_VARIABLES if env.get(k, "").strip()}
    return facts


def _rclpy_facts(env: Mapping[str, str]) -> dict[str, Any]:
    from importlib import metadata

    import rclpy
    from rclpy.utilities import get_rmw_implementation_identifier

    distro, distro_from = rclpy_distro(env)
    version = None
    for name in (f"ros-{distro}-rclpy", "ros-rclpy", "rclpy"):
        try:
            version = metadata.version(name)
            break
        except metadata.PackageNotFoundError:
            continue
    rmw = get_rmw_implementation_identifier()
    scope, scope_from = rclpy_range(env)
    return {
        "rclpy": {"version": version, "path": os.path.dirname(rclpy.__file__ or "")},
        "rmw": rmw, "rmw_from": "RMW_IMPLEMENTATION" if env.get("RMW_IMPLEMENTATION") else "the default RMW",
        "distro": distro, "distro_from": distro_from,
        "discovery_range": scope, "discovery_range_from": scope_from,
    }  # fmt: skip


def _dds_facts(env: Mapping[str, str]) -> dict[str, Any]:
    from importlib import metadata

    from rostool.graph.ros2_base import env as ros2_env
    from rostool.interfaces.ros2_types import distro_from_env

    try:
        cyclone = metadata.version("cyclonedds")
    except metadata.PackageNotFoundError:
        cyclone = "?"
    named = env.get("ROS_DISTRO", "").strip()
    scope: str | None
    try:
        scope, scope_from = ros2_env.discovery_range_reason(env)
    except Exception as err:
        scope, scope_from = None, str(err)
    return {
        "rmw": f"none: rostool's own DDS, cyclonedds {cyclone}, on the wire as rmw_cyclonedds_cpp",
        "rmw_from": "no rclpy",
        "distro": distro_from_env(env),
        "distro_from": "ROS_DISTRO" if named else "rostool's default: ROS_DISTRO is unset",
        "discovery_range": scope,
        "discovery_range_from": scope_from,
    }
