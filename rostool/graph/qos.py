"""QoS as the user asks for it (`--qos-*`): one value every backend accepts; ROS 2 turns it into DDS
policies, ROS 1 refuses it when given (its topics have no QoS)."""

from __future__ import annotations

from dataclasses import dataclass, fields

# rmw's presets (rmw/qos_profiles.h) by ros2cli's short keys: the keys of
# rostool.graph.ros2_base.qos.PROFILES.
PROFILE_NAMES = (
    "default", "parameter_events", "parameters", "sensor_data", "services_default", "system_default"
)  # fmt: skip
# the policies' values by rclpy's short keys (as ros2cli's --qos-* take them); "system_default" leaves the
# middleware's default
RELIABILITY_NAMES = ("system_default", "reliable", "best_effort")
DURABILITY_NAMES = ("system_default", "transient_local", "volatile")
HISTORY_NAMES = ("system_default", "keep_last", "keep_all")
LIVELINESS_NAMES = ("system_default", "automatic", "manual_by_topic")


@dataclass(frozen=True)
class QosRequest:
    """What the user asked for on the command line (None: not given)."""

    profile: str | None = None
    reliability: str | None = None
    durability: str | None = None
    depth: int | None = None
    history: str | None = None
    liveliness: str | None = None
    lease_duration: float | None = None  # seconds (liveliness lease); < 0 or 0: not given, as ros2cli

    @property
    def given(self) -> bool:
        return any(getattr(self, f.name) is not None for f in fields(self))
