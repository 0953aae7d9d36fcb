"""QoS between rostool's profiles (the QosProfile the verbs' --qos-* become) and
rclpy's, both ways."""

from __future__ import annotations

from typing import Any

from rostool.graph.ros2_base.qos import QosProfile


def to_rclpy(profile: QosProfile) -> Any:
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    depth = profile.depth
    history = HistoryPolicy.SYSTEM_DEFAULT if depth is None else HistoryPolicy.KEEP_LAST
    if depth == 0:
        history = HistoryPolicy.KEEP_ALL
    reliability = {"reliable": ReliabilityPolicy.RELIABLE, "best_effort": ReliabilityPolicy.BEST_EFFORT}
    durability = {"volatile": DurabilityPolicy.VOLATILE, "transient_local": DurabilityPolicy.TRANSIENT_LOCAL}
    return QoSProfile(
        history=history,
        depth=depth or 0,
        reliability=reliability.get(profile.reliability or "", ReliabilityPolicy.SYSTEM_DEFAULT),
        durability=durability.get(profile.durability or "", DurabilityPolicy.SYSTEM_DEFAULT),
    )


def from_rclpy(qos: Any) -> QosProfile:
    """rostool's view of an endpoint's QoS as rmw reports it; a history rmw does not know (Fast DDS's
    remote endpoints) is an unknown depth, as the DDS backend and ros2cli show it."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, ReliabilityPolicy

    reliability = "best_effort" if qos.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable"
    if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL:
        durability = "transient_local"
    elif qos.durability in (DurabilityPolicy.VOLATILE, DurabilityPolicy.SYSTEM_DEFAULT):
        durability = "volatile"
    else:
        durability = str(qos.durability.name).lower()
    if qos.history == HistoryPolicy.KEEP_ALL:
        return QosProfile(reliability, durability, 0)
    if qos.history == HistoryPolicy.KEEP_LAST:
        return QosProfile(reliability, durability, int(qos.depth))
    return QosProfile(reliability, durability, None)
