"""The DDS side of a ROS 2 process: domain id, discovery range, Cyclone configuration, QoS, raw samples.

Mirrors what rmw does when rclcpp/rclpy create a context (Iron and later), as a real rclpy node on the
same machine with the same environment sees the graph (tests/test_across_machines.py holds the matrix):
- ROS_AUTOMATIC_DISCOVERY_RANGE unset or SUBNET (ROS 2's default): Cyclone's defaults, multicast on the
  interface it picks; ROS_STATIC_PEERS are also asked by unicast (through routers, where no multicast goes).
- LOCALHOST: multicast off, 127.0.0.1 as a static peer, participant index `auto` with at most 32
  participants per host. With no static peers rostool also binds to 127.0.0.1 only (Cyclone would listen
  on 0.0.0.0), so nothing it does leaves the machine; with static peers it uses the machine's interfaces,
  as it must to reach them.
- OFF: multicast off and a per-process discovery tag; SYSTEM_DEFAULT: Cyclone's own settings. Static peers
  are ignored in both, as rmw does. ROS_LOCALHOST_ONLY=1 (deprecated) forces LOCALHOST.
- CYCLONEDDS_URI, when set, is appended after that generated fragment, so the user's file wins.
- the participant's USER_DATA is `enclave=/;`.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Mapping
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.ros2_base.env import discovery_range, domain_id, static_peers
from rostool.graph.ros2_base.qos import QosProfile

MAX_PARTICIPANTS_PER_HOST = 32


def _xml_attr(text: str) -> str:
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")


def cyclone_config(env: Mapping[str, str] = os.environ) -> str:
    """The configuration string for `Domain(id, config)`: generated fragment, then CYCLONEDDS_URI."""
    scope = discovery_range(env)
    peers = [] if scope in ("OFF", "SYSTEM_DEFAULT") else static_peers(env)
    general = ""
    discovery = ""
    if scope == "LOCALHOST":
        general = "<AllowMulticast>false</AllowMulticast>"
        if loopback_only(env):
            # Cyclone refuses an interface selected twice (`lo` by the user, 127.0.0.1 by us): theirs wins
            general = '<Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>' + general
        peers = ["127.0.0.1", *peers]
    elif scope == "OFF":
        general = "<AllowMulticast>false</AllowMulticast>"
        discovery = f"<ParticipantIndex>none</ParticipantIndex><Tag>ros_discovery_off_{os.getpid()}</Tag>"
    if scope in ("LOCALHOST", "SUBNET") and (peers or scope == "LOCALHOST"):
        discovery = (
            "<ParticipantIndex>auto</ParticipantIndex>"
            f"<MaxAutoParticipantIndex>{MAX_PARTICIPANTS_PER_HOST}</MaxAutoParticipantIndex>"
        )
    if peers:
        discovery += "<Peers>" + "".join(f'<Peer address="{_xml_attr(p)}"/>' for p in peers) + "</Peers>"
    body = (f"<General>{general}</General>" if general else "") + (
        f"<Discovery>{discovery}</Discovery>" if discovery else ""
    )
    # Fast DDS 3 (Kilted) announces type objects with try_construct 0, which Cyclone rejects as invalid
    # and then never matches those endpoints (ros_discovery_info, services, actions); accept them
    body += "<Compatibility><AllowInvalidTryConstruct>true</AllowInvalidTryConstruct></Compatibility>"
    # Fast DDS honours a discovery disposal (a reader, writer or participant deleted) only when it carries
    # the key hash; without it an exited rostool's endpoints stay in ROS 2 tools' view until its lease ends
    body += "<Internal><GenerateKeyhash>true</GenerateKeyhash></Internal>"
    parts = [f'<CycloneDDS><Domain Id="any">{body}</Domain></CycloneDDS>']
    user = env.get("CYCLONEDDS_URI", "").strip()
    if user:
        parts.append(user)
    return ",".join(parts)


def loopback_only(env: Mapping[str, str] = os.environ) -> bool:
    """Whether this environment keeps DDS on 127.0.0.1: LOCALHOST with no static peer to reach elsewhere and
    no interface chosen by the user's CYCLONEDDS_URI."""
    return (
        discovery_range(env) == "LOCALHOST"
        and not static_peers(env)
        and not _user_selects_interfaces(env.get("CYCLONEDDS_URI", ""))
    )


def _user_selects_interfaces(uri: str) -> bool:
    """Whether CYCLONEDDS_URI (inline XML, file:// URIs or paths, comma-separated) names interfaces."""
    for part in (p.strip() for p in uri.split(",")):
        text = part
        if not part.startswith("<"):
            path = part.removeprefix("file://")
            try:
                with open(os.path.expandvars(path), encoding="utf-8", errors="replace") as handle:
                    text = handle.read()
            except OSError:
                continue
        lowered = text.lower()
        if "<interfaces" in lowered or "<networkinterfaceaddress" in lowered:
            return True
    return False


def silence_cyclone_log() -> None:
    """Cyclone prints its own errors and warnings on stderr (for instance about the XTypes type objects
    Fast DDS 3 announces); rostool reports what matters to the user in its own words, so only Cyclone's
    fatal errors stay. There is no Python API for the log mask: call the C one in the library the binding
    loaded (the wheel ships a second libddsc that would keep its own mask)."""
    import ctypes

    import cyclonedds._clayer  # noqa: F401  (loads libddsc)

    with contextlib.suppress(OSError), open("/proc/self/maps", encoding="utf-8") as maps:
        paths = {line.split()[-1] for line in maps if "/libddsc" in line}
        for path in paths:
            ctypes.CDLL(path).dds_set_log_mask(ctypes.c_uint32(DDS_LC_FATAL))


DDS_LC_FATAL = 1


def free_qos_copies() -> None:
    """cyclonedds-python (11.0.1) reads USER_DATA, TOPIC_DATA and GROUP_DATA out of a C QoS with
    dds_qget_userdata (and co.), which hands back a copy the caller must dds_free, and never frees it: every
    built-in topic sample taken leaked its USER_DATA (a ROS 2 endpoint's `typehash=...;`, a participant's
    `enclave=/;`). A long-lived graph lost ~2 KiB per participant that came and went (heaptrack: 460 KiB in
    5,617 copies over 4 minutes of churn), the graph daemon's RSS growing 0.06-0.14 MiB a minute. The three
    getters are replaced by ones that free their copy (and keep it in locals: the library's share one
    buffer between threads)."""
    import ctypes

    from cyclonedds.qos import Policy, _CQos

    if getattr(_CQos, "_rostool_frees_copies", False):
        return

    def getter(name: str, policy: Any) -> Any:
        def read(cls: Any, qos: Any) -> Any:
            value, size = ctypes.c_void_p(), ctypes.c_size_t()
            if not getattr(cls, name)(qos, ctypes.byref(value), ctypes.byref(size)):
                return None
            try:
                return policy(data=ctypes.string_at(value, size.value)) if size.value and value else None
            finally:
                if value:
                    cls.free(value)

        return classmethod(read)

    _CQos._get_p_userdata = getter("_get_userdata", Policy.Userdata)
    _CQos._get_p_topicdata = getter("_get_topicdata", Policy.Topicdata)
    _CQos._get_p_groupdata = getter("_get_groupdata", Policy.Groupdata)
    _CQos._rostool_frees_copies = True


# --- QoS -------------------------------------------------------------------------------------------


def to_dds_qos(profile: QosProfile, user_data: bytes | None = None) -> Any:
    from cyclonedds.core import Policy, Qos
    from cyclonedds.util import duration

    policies: list[Any] = [
        # plain CDR (XCDR1), as rmw_cyclonedds_cpp announces; XCDR2-only peers would not match otherwise
        Policy.DataRepresentation(use_cdrv0_representation=True),
        # rmw_cyclonedds_cpp never auto-disposes on unregister
        Policy.WriterDataLifecycle(autodispose=False),
    ]
    if profile.reliability == "reliable":
        policies.append(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)))
    elif profile.reliability == "best_effort":
        policies.append(Policy.Reliability.BestEffort)
    if profile.durability == "transient_local":
        policies.append(Policy.Durability.TransientLocal)
    elif profile.durability == "volatile":
        policies.append(Policy.Durability.Volatile)
    if profile.depth is not None:
        keep_all = profile.depth == 0
        policies.append(Policy.History.KeepAll if keep_all else Policy.History.KeepLast(profile.depth))
    if profile.liveliness is not None or profile.lease_duration is not None:
        policies.append(_to_dds_liveliness(profile))
    if user_data:
        policies.append(Policy.Userdata(data=user_data))
    return Qos(*policies)


def from_dds_qos(qos: Any) -> QosProfile:
    """The ROS 2 view of an endpoint's discovered QoS."""
    from cyclonedds.core import Policy

    reliability = qos[Policy.Reliability]
    durability = qos[Policy.Durability]
    history = qos[Policy.History]
    rel = "best_effort" if reliability is Policy.Reliability.BestEffort else "reliable"
    if durability is Policy.Durability.Volatile or durability is None:
        dur = "volatile"
    elif durability is Policy.Durability.TransientLocal:
        dur = "transient_local"
    else:
        dur = str(getattr(durability, "__name__", durability)).lower()
    liveliness, lease = _from_dds_liveliness(qos[Policy.Liveliness])
    if history is None:  # not announced (Fast DDS never sends it): unknown, as ros2cli shows it
        return QosProfile(rel, dur, None, liveliness, lease)
    depth = getattr(history, "depth", 0 if history is Policy.History.KeepAll else 1)
    return QosProfile(rel, dur, int(depth), liveliness, lease)


def _to_dds_liveliness(profile: QosProfile) -> Any:
    from cyclonedds.core import Policy
    from cyclonedds.util import duration

    seconds = profile.lease_duration
    lease = duration(infinite=True) if seconds is None else duration(seconds=seconds)
    if profile.liveliness == "manual_by_topic":
        return Policy.Liveliness.ManualByTopic(lease_duration=lease)
    return Policy.Liveliness.Automatic(lease_duration=lease)


def _from_dds_liveliness(policy: Any) -> tuple[str | None, float | None]:
    """An endpoint's announced liveliness kind and lease (seconds; None: infinite); not announced: DDS's
    default (automatic, infinite)."""
    from cyclonedds.core import Policy
    from cyclonedds.util import duration

    if policy is None:
        return None, None
    kind = "manual_by_topic" if isinstance(policy, Policy.Liveliness.ManualByTopic) else "automatic"
    if isinstance(policy, Policy.Liveliness.ManualByParticipant):
        kind = "manual_by_participant"
    lease = policy.lease_duration
    return kind, None if lease >= duration(infinite=True) else lease / 1e9


def user_data_of(qos: Any) -> bytes:
    from cyclonedds.core import Policy

    policy = qos[Policy.Userdata]
    return bytes(policy.data) if policy is not None else b""


# DDS QosPolicyId_t values (DDS 1.4, table 2.2.3), as in Cyclone's incompatible-QoS statuses.
POLICY_NAMES = {
    1: "USER_DATA", 2: "DURABILITY", 3: "PRESENTATION", 4: "DEADLINE", 5: "LATENCY_BUDGET",
    6: "OWNERSHIP", 7: "OWNERSHIP_STRENGTH", 8: "LIVELINESS", 9: "TIME_BASED_FILTER", 10: "PARTITION",
    11: "RELIABILITY", 12: "DESTINATION_ORDER", 13: "HISTORY", 14: "RESOURCE_LIMITS",
    23: "DATA_REPRESENTATION", 24: "TYPE_CONSISTENCY_ENFORCEMENT",
}  # fmt: skip


def wakeable_waitset(participant: Any) -> Any:
    """A cyclonedds WaitSet with a guard condition attached as `wakeup`: `wakeup.set(True)` ends a wait in
    progress at once (WaitSet.set_trigger does not: the wait runs to its timeout)."""
    from cyclonedds.core import GuardCondition, WaitSet

    waitset = WaitSet(participant)
    waitset.wakeup = GuardCondition(participant)
    waitset.attach(waitset.wakeup)
    return waitset


class Participant:
    """One DDS domain participant configured like an rmw_cyclonedds_cpp context."""

    def __init__(self, env: Mapping[str, str] = os.environ) -> None:
        from cyclonedds.core import DDSException, Policy, Qos
        from cyclonedds.domain import Domain, DomainParticipant

        self.domain_id = domain_id(env)
        self.range = discovery_range(env)
        config = cyclone_config(env)
        silence_cyclone_log()
        free_qos_copies()
        if loopback_only(env):
            from rostool.graph.ros2.loopback_bind import bind_to_loopback

            bind_to_loopback()  # Cyclone would listen on 0.0.0.0 too
        try:
            self._domain = Domain(self.domain_id, config) if config else None
            self.dp = DomainParticipant(self.domain_id, qos=Qos(Policy.Userdata(data=b"enclave=/;")))
        except DDSException as err:
            hint = " (check CYCLONEDDS_URI)" if env.get("CYCLONEDDS_URI") else ""
            raise RostoolError(f"cannot start DDS on domain {self.domain_id}: {err}{hint}") from err
        self.guid: bytes = self.dp.guid.bytes

    def close(self) -> None:
        # Deleting the participant deletes its readers and writers; remote peers see them disposed.
        from cyclonedds.core import DDSException

        with contextlib.suppress(DDSException):
            self.dp._delete(self.dp._ref)
        self._domain = None
