"""QoS as the user asks for it (`--qos-*`): one value every backend accepts; ROS 2 turns it into DDS
policies, ROS 1 refuses it when given (its topics have no QoS)."""

from __future__ import annotations

from dataclasses import dataclass

# rmw's presets (rmw/qos_profiles.h) by ros2cli's short keys: the keys of
# rostool.graph.ros2_base.qos.PROFILES.
PROFILE_NAMES = (
    "default", "parameter_events", "parameters", "sensor_data", "services_default", "system_default"
)  # fmt: skip


@dataclass(frozen=True)
class QosRequest:
    """What the user asked for on the command line (None: not given)."""

    profile: str | None = None
    reliability: str | None = None
    durability: str | None = None
    depth: int | None = None

    @property
    def given(self) -> bool:
        return any(v is not None for v in (self.profile, self.reliability, self.durability, self.depth))
