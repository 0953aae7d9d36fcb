"""ROS 2 QoS as the verbs choose it, whichever transport applies it: the profiles (rmw's presets), the
user's --qos-* request, DDS's request/offer rule and ros2cli's adaptation to the publishers' QoS."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from rostool.graph import qos


@dataclass(frozen=True)
class QosProfile:
    """The ROS 2 QoS policies the verbs choose; None leaves the DDS default."""

    reliability: str | None = "reliable"  # reliable | best_effort
    durability: str | None = "volatile"  # volatile | transient_local
    depth: int | None = 10  # keep last N; 0 = keep all

    def describe(self) -> str:
        default = "system default"
        return f"{self.reliability or default}, {self.durability or default}, depth {self.depth}"


def serves(writer: QosProfile, reader: QosProfile) -> bool:
    """DDS's request/offer rule for the policies rostool sets; unset policies are DDS's defaults
    (writers reliable, readers best effort, both volatile)."""
    if reader.reliability == "reliable" and (writer.reliability or "reliable") != "reliable":
        return False
    return not (reader.durability == "transient_local" and writer.durability != "transient_local")


# rmw's presets (rmw/qos_profiles.h), by ros2cli's short keys.
PROFILES: dict[str, QosProfile] = {
    "default": QosProfile("reliable", "volatile", 10),
    "sensor_data": QosProfile("best_effort", "volatile", 5),
    "system_default": QosProfile(None, None, None),
    "services_default": QosProfile("reliable", "volatile", 10),
    "parameters": QosProfile("reliable", "volatile", 1000),
    "parameter_events": QosProfile("reliable", "volatile", 1000),
}


@dataclass(frozen=True)
class QosRequest(qos.QosRequest):
    """The user's request (rostool.graph.qos) with the DDS profiles it stands for."""

    def base(self) -> QosProfile:
        return PROFILES[self.profile or "default"]

    def apply(self, profile: QosProfile) -> QosProfile:
        """`profile` with every explicitly given policy replacing its own."""
        changes: dict[str, Any] = {}
        if self.reliability is not None:
            changes["reliability"] = self.reliability
        if self.durability is not None:
            changes["durability"] = self.durability
        if self.depth is not None:
            changes["depth"] = self.depth
        return replace(profile, **changes)


def adapt_to_publishers(request: QosRequest, offered: list[QosProfile]) -> tuple[QosProfile, list[str]]:
    """ros2cli's choice for echo/hz: reliable only when every publisher is, transient_local only when every
    publisher is; explicitly requested policies win. Returns the profile and notes for the user."""
    profile = request.base()
    notes: list[str] = []
    if offered:
        reliable = sum(1 for q in offered if q.reliability == "reliable")
        durable = sum(1 for q in offered if q.durability == "transient_local")
        adapted = replace(
            profile,
            reliability="reliable" if reliable == len(offered) else "best_effort",
            durability="transient_local" if durable == len(offered) else "volatile",
        )
        if 0 < reliable < len(offered) and request.reliability is None:
            notes.append("some, but not all, publishers are offering reliable; subscribing best_effort")
        if 0 < durable < len(offered) and request.durability is None:
            notes.append("some, but not all, publishers are offering transient_local; subscribing volatile")
        profile = adapted
    return request.apply(profile), notes
