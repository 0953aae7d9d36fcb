"""QoS between rostool's profiles (the QosProfile the verbs' --qos-* become) and
rclpy's, both ways."""

from __future__ import annotations

from typing import Any

from rostool.graph.ros2_base.qos import QosProfile


def to_rclpy(profile: QosProfile) -> Any:
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile, ReliabilityPolicy

    depth = profile.depth
    history = HistoryPolicy.SYSTEM_DEFAULT if depth is None else HistoryPolicy.KEEP_LAST
    if depth == 0:
        history = HistoryPolicy.KEEP_ALL
    reliability = {"reliable": ReliabilityPolicy.RELIABLE, "best_effort": ReliabilityPolicy.BEST_EFFORT}
    durability = {"volatile": DurabilityPolicy.VOLATILE, "transient_local": DurabilityPolicy.TRANSIENT_LOCAL}
    liveliness = {
        "automatic": LivelinessPolicy.AUTOMATIC,
        "manual_by_topic": LivelinessPolicy.MANUAL_BY_TOPIC,
    }
    # no lease given: rmw's default (unspecified, which DDS reads as infinite)
    lease = (
        {}
        if profile.lease_duration is None
        else {"liveliness_lease_duration": Duration(seconds=profile.lease_duration)}
    )
    return QoSProfile(
        history=history,
        depth=depth or 0,
        reliability=reliability.get(profile.reliability or "", ReliabilityPolicy.SYSTEM_DEFAULT),
        durability=durability.get(profile.durability or "", DurabilityPolicy.SYSTEM_DEFAULT),
        liveliness=liveliness.get(profile.liveliness or "", LivelinessPolicy.SYSTEM_DEFAULT),
        **lease,
    )


def from_rclpy(qos: Any) -> QosProfile:
    """rostool's view of an endpoint's QoS as rmw reports it; a history rmw does not know (Fast DDS's
    remote endpoints) is an unknown depth, as the DDS backend and ros2cli show it."""
    from rclpy.duration import Infinite
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, ReliabilityPolicy

    reliability = "best_effort" if qos.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable"
    if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL:
        durability = "transient_local"
    elif qos.durability in (DurabilityPolicy.VOLATILE, DurabilityPolicy.SYSTEM_DEFAULT):
        durability = "volatile"
    else:
        durability = str(qos.durability.name).lower()
    liveliness = (
        None if qos.liveliness == LivelinessPolicy.SYSTEM_DEFAULT else str(qos.liveliness.name).lower()
    )
    lease_ns = qos.liveliness_lease_duration.nanoseconds
    lease = None if lease_ns >= Infinite.nanoseconds else lease_ns / 1e9
    if qos.history == HistoryPolicy.KEEP_ALL:
        depth: int | None = 0
    elif qos.history == HistoryPolicy.KEEP_LAST:
        depth = int(qos.depth)
    else:
        depth = None
    return QosProfile(reliability, durability, depth, liveliness, lease)
