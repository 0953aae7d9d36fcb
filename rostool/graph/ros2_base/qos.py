"""ROS 2 QoS as the verbs choose it, whichever transport applies it: the profiles (rmw's presets), the
user's --qos-* request, DDS's request/offer rule and ros2cli's adaptation to the publishers' QoS."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any

from rostool.graph import qos
from rostool.graph.base import TopicEndpointQos


@dataclass(frozen=True)
class QosProfile:
    """The ROS 2 QoS policies the verbs choose; None leaves the DDS default."""

    reliability: str | None = "reliable"  # reliable | best_effort
    durability: str | None = "volatile"  # volatile | transient_local
    depth: int | None = 10  # keep last N; 0 = keep all
    liveliness: str | None = None  # automatic | manual_by_topic (None: DDS's default, automatic)
    lease_duration: float | None = None  # the liveliness lease in seconds (None: infinite)

    def endpoint_facts(self) -> TopicEndpointQos:
        """What topic info -v shows of an endpoint's QoS; liveliness only when not DDS's default
        (automatic, infinite lease)."""
        facts: TopicEndpointQos = {
            "reliability": self.reliability, "durability": self.durability, "depth": self.depth
        }  # fmt: skip
        if self.liveliness not in (None, "automatic") or self.lease_duration is not None:
            facts["liveliness"] = self.liveliness
            facts["liveliness_lease_duration"] = self.lease_duration
        return facts

    def describe(self) -> str:
        default = "system default"
        text = f"{self.reliability or default}, {self.durability or default}, depth {self.depth}"
        if self.liveliness is not None or self.lease_duration is not None:
            lease = "infinite" if self.lease_duration is None else f"{self.lease_duration:g} s"
            text += f", liveliness {self.liveliness or 'automatic'} (lease {lease})"
        return text


def serves(writer: QosProfile, reader: QosProfile) -> bool:
    """DDS's request/offer rule for the policies rostool sets; unset policies are DDS's defaults
    (writers reliable, readers best effort, both volatile)."""
    if reader.reliability == "reliable" and (writer.reliability or "reliable") != "reliable":
        return False
    if reader.durability == "transient_local" and writer.durability != "transient_local":
        return False
    # liveliness: the writer's kind at least the reader's, its lease at most the reader's
    if _LIVELINESS_RANK.get(writer.liveliness, 0) < _LIVELINESS_RANK.get(reader.liveliness, 0):
        return False
    return reader.lease_duration is None or (
        writer.lease_duration is not None and writer.lease_duration <= reader.lease_duration
    )


_LIVELINESS_RANK = {None: 0, "automatic": 0, "manual_by_participant": 1, "manual_by_topic": 2}


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

    @classmethod
    def of(cls, request: qos.QosRequest) -> QosRequest:
        return cls(**{f.name: getattr(request, f.name) for f in fields(request)})

    def base(self) -> QosProfile:
        return PROFILES[self.profile or "default"]

    def apply(self, profile: QosProfile) -> QosProfile:
        """`profile` with every explicitly given policy replacing its own, as ros2cli's
        profile_configure_short_keys does ("system_default": the middleware's default; a lease of 0 or
        less: not given)."""
        changes: dict[str, Any] = {}
        for policy in ("reliability", "durability", "liveliness"):
            value = getattr(self, policy)
            if value is not None:
                changes[policy] = None if value == "system_default" else value
        if self.lease_duration is not None and self.lease_duration > 0:
            changes["lease_duration"] = self.lease_duration
        changes["depth"] = _depth(self.history, self.depth, profile.depth)
        return replace(profile, **changes)


def _depth(history: str | None, depth: int | None, base: int | None) -> int | None:
    """rostool's depth (None: the middleware's history, 0: keep all, N: keep last N) from --qos-history,
    --qos-depth and the profile's own."""
    if history == "keep_all":
        return 0
    if depth is not None:
        return depth
    if history == "system_default":
        return None
    if history == "keep_last" and not base:  # keep last of a profile without a depth: the smallest
        return 1
    return base


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
