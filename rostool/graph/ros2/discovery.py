"""The ROS 2 graph as rmw_dds_common's GraphCache sees it: DDS built-in topics plus `ros_discovery_info`.

DCPSParticipant/DCPSPublication/DCPSSubscription give every participant, writer and reader (GUID, topic,
type, QoS, USER_DATA). Nodes are not DDS entities: each ROS 2 context publishes one
rmw_dds_common/msg/ParticipantEntitiesInfo on `ros_discovery_info` (reliable, transient-local, keep last
1), listing its nodes and the GIDs of their readers and writers. A GID is the entity's 16-byte DDS GUID
(zero-padded to 24 bytes up to Humble, where rmw_dds_common/msg/Gid was `char[24]`).
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from typing import Any

from rostool.graph.ros2 import dds
from rostool.graph.ros2_base.names import from_dds_topic, from_dds_type
from rostool.graph.ros2_base.qos import QosProfile

DISCOVERY_TOPIC = "ros_discovery_info"
DISCOVERY_TYPE = "rmw_dds_common/msg/ParticipantEntitiesInfo"
EPROSIMA = b"\x01\x0f"  # the vendor id that starts a Fast DDS participant's GUID prefix
ENDPOINTS_GRACE = 4.0  # seconds a participant may take to describe itself (Fast DDS: two heartbeats)
# A participant's endpoints come in one burst per SEDP writer (Fast DDS's answer to one NACK): once every
# participant has shown both kinds, the rest of a burst follows within milliseconds (measured: at most 4 ms
# after, in 28 cold listings of 10 Fast DDS peers at load 11-14), so a short quiet spell ends the wait.
DESCRIBED_QUIET = 0.03
# ...but not when a participant has more endpoints of one kind than Cyclone asks for at once: an ACKNACK
# names at most 128 missing samples (its reorder window, Internal/PrimaryReorderMaxSamples' default). An
# rclpy process of 11 nodes with 4 publishers each has 144 writers (a Jazzy node makes 9 of its own); on
# the wire: HEARTBEAT 1..144, ACKNACK 1/128, writers 1..128 at once, then ACKNACK 129/16 100 ms later,
# answered with 10, then ACKNACK 139/6 another 100 ms later (30-100 ms in cold listings): the quiet spell
# ended between them, and the listing lacked the last node's publishers, the last entities it made. So
# whenever a participant's ros_discovery_info is known, every GID it names must have come by SEDP (the
# GIDs are the endpoints' GUIDs); before that sample, a participant that showed a whole window of one kind
# is waited for (its sample comes 10-50 ms after the burst, see defer_info_reader)
SEDP_WINDOW = 128
# ...within a bound: a participant whose endpoints brought nothing new for this long has described all it
# will (a GID it still names is an endpoint deleted since, or its sample never came)
NAMED_STALL = 1.0
POLL_SECONDS = 0.01  # how often a settle looks: the quiet spell is measured at this grain
# ros_discovery_info's reader is made once the participants seen have described their endpoints, at the
# latest this long after discovery started (see GraphCache.defer_info_reader)
INFO_READER_LATEST = 2.5
# A participant whose ros_discovery_info writer is known this long without its sample is asked again by a
# new reader (see GraphCache._prompt_newcomers), at most once every PROMPT_EVERY seconds
PROMPT_AFTER = 0.1
PROMPT_EVERY = 0.25
PROMPT_GIVE_UP = 5.0  # by then the writer's own heartbeat (3 s) has brought the sample, if it ever comes


@dataclass
class Endpoint:
    guid: bytes
    participant: bytes
    dds_topic: str
    dds_type: str
    qos: QosProfile
    user_data: bytes
    is_writer: bool

    @property
    def ros(self) -> tuple[str, str] | None:
        return from_dds_topic(self.dds_topic)

    @property
    def type_name(self) -> str:
        return from_dds_type(self.dds_type)

    @property
    def type_hash(self) -> str:
        for part in self.user_data.decode("utf-8", "replace").split(";"):
            if part.startswith("typehash="):
                return part.removeprefix("typehash=")
        return ""


@dataclass
class NodeEntry:
    """One node of a participant as ros_discovery_info describes it, with its readers' and writers' GIDs."""

    namespace: str
    name: str
    readers: list[bytes] = field(default_factory=list)
    writers: list[bytes] = field(default_factory=list)

    @property
    def full_name(self) -> str:
        return self.namespace.rstrip("/") + "/" + self.name


# --- ParticipantEntitiesInfo CDR ---------------------------------------------------------------------


def encode_entities_info(participant: bytes, nodes: Iterable[NodeEntry], gid_size: int) -> bytes:
    """XCDR1 little endian, with the Gid layout of the distro (`gid_size` 16 or 24)."""
    out = bytearray(b"\x00\x01\x00\x00")

    def align(n: int) -> None:
        out.extend(b"\0" * (-(len(out) - 4) % n))

    def gid(value: bytes) -> None:
        out.extend(value[:gid_size].ljust(gid_size, b"\0"))

    def string(text: str) -> None:
        data = text.encode() + b"\0"
        align(4)
        out.extend(struct.pack("<I", len(data)))
        out.extend(data)

    def gids(values: list[bytes]) -> None:
        align(4)
        out.extend(struct.pack("<I", len(values)))
        for value in values:
            gid(value)

    gid(participant)
    entries = list(nodes)
    align(4)
    out.extend(struct.pack("<I", len(entries)))
    for node in entries:
        string(node.namespace)
        string(node.name)
        gids(node.readers)
        gids(node.writers)
    align(4)
    return bytes(out)


def decode_entities_info(raw: bytes) -> tuple[bytes, list[NodeEntry]]:
    """Participant GID and nodes; tries the Iron+ 16-byte GID first, then Humble's 24 bytes."""
    for size in (16, 24):
        try:
            return _decode(raw, size)
        except (ValueError, struct.error, UnicodeDecodeError):
            continue
    raise ValueError("not a ParticipantEntitiesInfo sample")


def _decode(raw: bytes, gid_size: int) -> tuple[bytes, list[NodeEntry]]:
    if len(raw) < 4 or raw[0] != 0 or raw[1] not in (0, 1):
        raise ValueError("bad encapsulation")
    order = "<" if raw[1] == 1 else ">"
    pos = 4

    def align(n: int) -> None:
        nonlocal pos
        pos += -(pos - 4) % n

    def u32() -> int:
        nonlocal pos
        align(4)
        (value,) = struct.unpack_from(order + "I", raw, pos)
        pos += 4
        return int(value)

    def take(n: int) -> bytes:
        nonlocal pos
        if pos + n > len(raw):
            raise ValueError("truncated")
        data = raw[pos : pos + n]
        pos += n
        return data

    def string() -> str:
        length = u32()
        if not 1 <= length <= 4096:
            raise ValueError("bad string")
        data = take(length)
        if data[-1] != 0 or 0 in data[:-1]:
            raise ValueError("bad string")
        return data[:-1].decode()

    def gids() -> list[bytes]:
        count = u32()
        if count > 100_000:
            raise ValueError("bad count")
        return [take(gid_size)[:16] for _ in range(count)]

    participant = take(gid_size)[:16]
    count = u32()
    if count > 10_000:
        raise ValueError("bad count")
    nodes = []
    for _ in range(count):
        namespace, name = string(), string()
        nodes.append(NodeEntry(namespace, name, gids(), gids()))
    if len(raw) - pos > 7 or any(raw[pos:]):
        raise ValueError("trailing bytes")
    return participant, nodes


# --- the cache ---------------------------------------------------------------------------------------


def start_discovery() -> GraphCache:
    """A participant and its built-in readers, started before anything else a process imports or builds:
    remote participants describe themselves on their own schedule (Fast DDS about 1 s after it meets a new
    participant), so the sooner it exists, the sooner a listing can answer."""
    return GraphCache(dds.Participant())


class GraphCache:
    """Everything discovered so far; `poll()` folds in new built-in and ros_discovery_info samples
    (those once the session gives its ros_discovery_info reader: `info_reader`, or `defer_info_reader`)."""

    def __init__(self, participant: dds.Participant, info_reader: Any = None) -> None:
        from cyclonedds.builtin import (
            BuiltinDataReader,
            BuiltinTopicDcpsParticipant,
            BuiltinTopicDcpsPublication,
            BuiltinTopicDcpsSubscription,
        )

        self.participant = participant
        self.own = participant.guid
        self._lock = threading.RLock()
        dp = participant.dp
        self._participants_reader = BuiltinDataReader(dp, BuiltinTopicDcpsParticipant)
        self._publications_reader = BuiltinDataReader(dp, BuiltinTopicDcpsPublication)
        self._subscriptions_reader = BuiltinDataReader(dp, BuiltinTopicDcpsSubscription)
        self.info_reader = info_reader
        self._make_info_reader: Callable[[], Any] | None = None
        self._reader_factory: Callable[[], Any] | None = None
        self._prompt: Any = None  # a ros_discovery_info reader made for newcomers whose sample was missed
        self._prompt_made = 0.0
        self._unnamed: dict[bytes, float] = {}  # participant -> when its ros_discovery_info writer was seen
        self.participants: dict[bytes, bytes] = {}  # GUID -> USER_DATA
        self.first_seen: dict[bytes, float] = {}
        self.grew: dict[bytes, float] = {}  # participant -> when an endpoint of it last came
        self.endpoints: dict[bytes, Endpoint] = {}
        self.nodes: dict[bytes, list[NodeEntry]] = {}  # participant GUID -> its nodes
        self.started = time.monotonic()
        self.changed = self.started  # participants or endpoints last changed
        self.nodes_changed = self.started  # ros_discovery_info last changed
        self.long_lived = False  # settled once (the daemon's cache): later settles only poll

    def poll(self) -> bool:
        from cyclonedds.core import InstanceState

        changed = False
        with self._lock:
            for sample in self._take(self._participants_reader):
                key = sample.key.bytes
                if sample.sample_info.instance_state != InstanceState.Alive:
                    changed |= self.participants.pop(key, None) is not None
                    self.nodes.pop(key, None)
                    self.first_seen.pop(key, None)  # a long-lived cache keeps nothing of the gone
                    self.grew.pop(key, None)
                    self._unnamed.pop(key, None)
                    continue
                if key not in self.participants:
                    changed = True
                    self.first_seen.setdefault(key, time.monotonic())
                self.participants[key] = dds.user_data_of(sample.qos) if sample.qos is not None else b""
            for reader, is_writer in ((self._publications_reader, True), (self._subscriptions_reader, False)):
                for sample in self._take(reader):
                    key = sample.key.bytes
                    if sample.sample_info.instance_state != InstanceState.Alive:
                        changed |= self.endpoints.pop(key, None) is not None
                        continue
                    if key in self.endpoints or sample.qos is None:
                        continue
                    participant = sample.participant_key.bytes
                    qos = dds.from_dds_qos(sample.qos)
                    if participant.startswith(EPROSIMA):  # Fast DDS never announces its history depth
                        qos = replace(qos, depth=None)
                    self.endpoints[key] = Endpoint(
                        key, participant, sample.topic_name, sample.type_name, qos,
                        dds.user_data_of(sample.qos), is_writer,
                    )  # fmt: skip
                    changed = True
                    self.grew[participant] = time.monotonic()
                    if is_writer and sample.topic_name == DISCOVERY_TOPIC and participant != self.own:
                        self._unnamed.setdefault(participant, time.monotonic())
            if self._make_info_reader is not None and self._info_reader_due():
                self.info_reader, self._make_info_reader = self._make_info_reader(), None
                self._prompt_made = time.monotonic()  # it asks every writer known so far
            if changed:
                self.changed = time.monotonic()
            if self._poll_info():
                self.nodes_changed = time.monotonic()
                changed = True
            for gone in [key for key in self.nodes if key not in self.participants]:
                del self.nodes[gone]  # a leaver's last ros_discovery_info may come after it is gone
            self._prompt_newcomers()
        return changed

    def defer_info_reader(self, make: Callable[[], Any]) -> None:
        """Make ros_discovery_info's reader (`make()`) once every participant seen has described its
        endpoints (at the latest INFO_READER_LATEST s after discovery started). A Fast DDS participant
        heartbeats its ros_discovery_info writer to a reader as soon as it learns of it, then every 3 s;
        made before this participant knows that writer (Fast DDS describes it about 1.1 s after meeting a
        new participant), the reader misses that first heartbeat and gets the nodes 2-4 s after start;
        made after, 0.05-0.1 s after the endpoints (measured, 10 Fast DDS peers)."""
        with self._lock:
            self._make_info_reader = make
        self.poll()

    def prompt_with(self, make: Callable[[], Any]) -> None:
        """`make()` makes one more ros_discovery_info reader, for newcomers whose sample was missed (see
        `_prompt_newcomers`)."""
        with self._lock:
            self._reader_factory = make

    def _info_reader_due(self) -> bool:
        if time.monotonic() - self.started >= INFO_READER_LATEST:
            return True
        # the participants' first bursts are enough: the peer's ros_discovery_info writer (its first
        # endpoint) is known by then, and the sample may name endpoints that are still to come
        return any(key != self.own for key in self.participants) and self._described(False, whole=False)

    def _prompt_newcomers(self) -> None:
        """Ask again for the ros_discovery_info of participants whose writer is known but whose sample has
        not come. A Fast DDS writer sends its sample to a reader as soon as it learns of it, often before
        this participant has learnt of the writer (Fast DDS describes its endpoints about 1 s after meeting
        a participant), which drops it; the next chance is the writer's heartbeat, every 3 s, and a node
        living a few seconds may never be named. A reader made once the writer is known is matched with it
        at once, and the writer sends its sample to that new reader at once (as to the deferred first
        reader). One such reader at a time, replaced for later newcomers, deleted once none is waiting."""
        if self._reader_factory is None or self.info_reader is None:
            return
        now = time.monotonic()
        for done in [k for k, at in self._unnamed.items() if k in self.nodes or now - at > PROMPT_GIVE_UP]:
            del self._unnamed[done]
        if not self._unnamed:
            self._drop_prompt()
            return
        newest = max(self._unnamed.values())
        due = now - newest >= PROMPT_AFTER and now - self._prompt_made >= PROMPT_EVERY
        if newest > self._prompt_made and due:
            self._drop_prompt()
            self._prompt, self._prompt_made = self._reader_factory(), now

    def _drop_prompt(self) -> None:
        if self._prompt is not None:
            prompt, self._prompt = self._prompt, None
            if self._take_info(prompt, newcomers_only=True):
                self.nodes_changed = time.monotonic()
            prompt.__del__()  # cyclonedds deletes an entity only this way (or with its participant)

    def _poll_info(self) -> bool:
        changed = self.info_reader is not None and self._take_info(self.info_reader)
        if self._prompt is not None:
            changed |= self._take_info(self._prompt, newcomers_only=True)
        return changed

    def _take_info(self, reader: Any, newcomers_only: bool = False) -> bool:
        """Fold in a ros_discovery_info reader's samples; `newcomers_only` (a prompt reader's): only for
        participants not named yet, the first reader has the later samples of the others, in order."""
        from cyclonedds._clayer import ddspy_take  # type: ignore[import-not-found]
        from cyclonedds.core import InstanceState, SampleState, ViewState

        mask = SampleState.Any | ViewState.Any | InstanceState.Any
        changed = False
        named = set(self.nodes) if newcomers_only else set()
        while True:
            samples = ddspy_take(reader._ref, mask, 64)
            if isinstance(samples, int) or not samples:
                return changed
            for data, info in samples:
                if not info.valid_data:
                    continue
                try:
                    participant, nodes = decode_entities_info(data)
                except ValueError:
                    continue
                if participant == self.own or participant in named:
                    continue
                if self.nodes.get(participant) != nodes:
                    self.nodes[participant] = nodes
                    changed = True

    @staticmethod
    def _take(reader: Any) -> list[Any]:
        found: list[Any] = []
        while True:
            batch = reader.take(N=256)
            if not batch:
                return found
            found.extend(batch)

    def settle(
        self, minimum: float = 0.5, quiet: float = DESCRIBED_QUIET, maximum: float = 3.0, nodes: bool = False
    ) -> bool:
        """Wait until every participant found has announced its endpoints (and, with `nodes`, its
        ros_discovery_info) and discovery has been quiet for a while; True when any other participant was
        found. A participant that is seen is not yet described: Fast DDS answers Cyclone's first
        request for its endpoints only on its next heartbeat (about 1 s later) and sends ros_discovery_info
        on the heartbeat after that (up to 3 s), so waiting for quiet alone returns an empty graph. A
        participant with more endpoints than one request of Cyclone's brings them in rounds 30-100 ms
        apart, longer than a quiet spell: it is waited for until it has all its ros_discovery_info names
        (see SEDP_WINDOW), past `maximum` too while those rounds still come (NAMED_STALL at most)."""
        if self.long_lived:
            self.poll()
            with self._lock:
                return any(key != self.own for key in self.participants)
        while True:
            self.poll()
            now = time.monotonic()
            elapsed = now - self.started
            remote = any(key != self.own for key in self.participants)
            if elapsed >= maximum and not (elapsed < maximum + NAMED_STALL and self._tail_in_flight(nodes)):
                return remote
            # each participant's endpoints come in one burst per SEDP writer, so once every participant
            # has shown both kinds a short quiet spell is enough
            last = max(self.changed, self.nodes_changed) if nodes else self.changed
            if remote and elapsed >= minimum and now - last >= quiet and self._described(nodes):
                return remote
            time.sleep(POLL_SECONDS)

    def spin(self, seconds: float) -> bool:
        """Poll until `seconds` after discovery started, as ros2cli's --spin-time waits (a long-lived cache
        only polls); True when any other participant was found."""
        deadline = self.started + seconds
        while True:
            self.poll()
            if self.long_lived or time.monotonic() >= deadline:
                with self._lock:
                    return any(key != self.own for key in self.participants)
            time.sleep(min(0.05, max(0.0, deadline - time.monotonic())))

    def await_described(self, limit: float, nodes: bool = True, ignore: bytes | None = None) -> None:
        """Poll; then, for at most `limit` seconds, wait for participants seen within ENDPOINTS_GRACE to
        describe themselves (a long-lived cache's `settle`), but `ignore` (the asking process's own, which
        describes itself only once it needs to)."""
        deadline = time.monotonic() + limit
        self.poll()
        while time.monotonic() < deadline and not self._described(nodes, ignore):
            time.sleep(0.02)
            self.poll()

    def _described(self, nodes: bool, ignore: bytes | None = None, whole: bool = True) -> bool:
        """Every ROS 2 participant has both a reader and a writer (rmw creates ros_discovery_info's pair
        before any node), so one that shows only one kind yet is still being described; a bare DDS
        participant is waited for at most ENDPOINTS_GRACE seconds. `whole`: also every endpoint beyond
        the first burst (see `_tail_to_come`)."""
        with self._lock:
            counts: dict[bytes, list[int]] = {}  # participant -> [readers, writers]
            announcers = set()
            for endpoint in self.endpoints.values():
                counts.setdefault(endpoint.participant, [0, 0])[endpoint.is_writer] += 1
                if endpoint.is_writer and endpoint.dds_topic == DISCOVERY_TOPIC:
                    announcers.add(endpoint.participant)
            now = time.monotonic()
            for participant in self.participants:
                age = now - self.first_seen.get(participant, now)
                if participant in (self.own, ignore) or age > ENDPOINTS_GRACE:
                    continue
                count = counts.get(participant, [0, 0])
                if not all(count):
                    return False
                announces = participant in announcers
                if nodes and announces and participant not in self.nodes:
                    return False
                if whole and self._tail_to_come(participant, max(count), announces, now):
                    return False
            return True

    def _tail_in_flight(self, nodes: bool) -> bool:
        """Every participant has described itself but for the rounds after a first burst: a listing whose
        time is up gives those (bounded by NAMED_STALL), which come 30-100 ms apart, rather than list a
        process without its last nodes (a Fast DDS participant's first burst came after 3.1 s in 2 of 12
        cold listings at load 8)."""
        return self._described(nodes, whole=False) and not self._described(nodes)

    def _tail_to_come(self, participant: bytes, most: int, announces: bool, now: float) -> bool:
        """Whether a participant's endpoints beyond Cyclone's first request are still to come (see
        SEDP_WINDOW): its ros_discovery_info names GIDs that SEDP has not brought yet, or, before that
        sample, it showed a whole window of one kind. `most`: its endpoints of the more numerous kind."""
        if now - self.grew.get(participant, now) >= NAMED_STALL:
            return False
        entries = self.nodes.get(participant)
        if entries is None:
            return announces and most >= SEDP_WINDOW
        named = {gid for node in entries for gid in (*node.readers, *node.writers)}
        seen = len(named & self.endpoints.keys())
        # none seen: GIDs that are not the endpoints' GUIDs (not a DDS rmw as we know it), nothing to wait for
        return 0 < seen < len(named)

    # --- queries ---------------------------------------------------------------------------------
    def remote_endpoints(self) -> list[Endpoint]:
        with self._lock:
            return [e for e in self.endpoints.values() if e.participant != self.own]

    def node_of(self) -> dict[bytes, str]:
        """Endpoint GUID -> node full name, for every node announced by a live participant."""
        owners: dict[bytes, str] = {}
        with self._lock:
            for participant, nodes in self.nodes.items():
                if participant not in self.participants:
                    continue
                for node in nodes:
                    for gid in (*node.readers, *node.writers):
                        owners[gid] = node.full_name
        return owners

    def node_entries(self) -> list[NodeEntry]:
        with self._lock:
            return [
                node
                for participant, nodes in self.nodes.items()
                if participant in self.participants and participant != self.own
                for node in nodes
            ]
