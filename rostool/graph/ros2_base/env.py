"""What a ROS 2 process reads from its environment before it joins a graph, whichever transport carries
it: the domain id and the automatic discovery range (with ROS_STATIC_PEERS)."""

from __future__ import annotations

import os
from collections.abc import Mapping

from rostool.errors import RostoolError

DOMAIN_ID_MAX = 232  # ROS 2's documented maximum: higher ids map to UDP ports past the usable range
RANGES = ("LOCALHOST", "SUBNET", "OFF", "SYSTEM_DEFAULT")


def domain_id(env: Mapping[str, str] = os.environ) -> int:
    text = env.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return 0
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= DOMAIN_ID_MAX:
        raise RostoolError(f"ROS_DOMAIN_ID={text!r} is not valid: use an integer from 0 to {DOMAIN_ID_MAX}")
    return value


def discovery_range(env: Mapping[str, str] = os.environ) -> str:
    """ROS 2's automatic discovery range (Iron and later, as rcl reads it): SUBNET unless told otherwise;
    the deprecated ROS_LOCALHOST_ONLY=1 still forces LOCALHOST."""
    if env.get("ROS_LOCALHOST_ONLY", "").strip() == "1":
        return "LOCALHOST"
    text = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip().upper()
    if not text:
        return "SUBNET"
    if text not in RANGES:
        raise RostoolError(
            f"ROS_AUTOMATIC_DISCOVERY_RANGE={text!r} is not valid: use one of {', '.join(RANGES)}"
        )
    return text


def discovery_range_reason(env: Mapping[str, str] = os.environ) -> tuple[str, str]:
    """The discovery range and where it came from, as `doctor` says it."""
    scope = discovery_range(env)
    if env.get("ROS_LOCALHOST_ONLY", "").strip() == "1":
        return scope, "ROS_LOCALHOST_ONLY=1 (deprecated)"
    if env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip():
        return scope, "ROS_AUTOMATIC_DISCOVERY_RANGE"
    return scope, "ROS 2's default: ROS_AUTOMATIC_DISCOVERY_RANGE is unset"


def static_peers(env: Mapping[str, str] = os.environ) -> list[str]:
    return [peer.strip() for peer in env.get("ROS_STATIC_PEERS", "").split(";") if peer.strip()]
