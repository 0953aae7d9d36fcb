"""The Graph interface over DDS: ROS 2 topics, nodes and QoS the way rmw_cyclonedds_cpp puts them on the wire.

The DDS participant starts on first need. It announces one node, `/rostool_<pid>`, on ros_discovery_info
(so ROS 2 tools list it like any node) with the readers and writers it creates. Samples are moved as raw
CDR bytes (`ddspy_write` / `ddspy_take`, the calls cyclonedds' own DataWriter/DataReader make after
serializing), so what goes out and what comes in is exactly rosbags' CDR, byte for byte.

A process that publishes also serves `<node>/get_type_description` (REP 2016), and a subscription to a type
rostool does not know asks the publisher's node for it (type_description.py).
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any, Literal

from rostool.errors import RostoolError
from rostool.graph.base import NodeInfo, Received, Subscription, TopicInfo
from rostool.graph.ros2 import dds
from rostool.graph.ros2.discovery import (
    DISCOVERY_TOPIC,
    DISCOVERY_TYPE,
    UNKNOWN_NODE,
    Endpoint,
    GraphCache,
    NodeEntry,
    encode_entities_info,
)
from rostool.graph.ros2.names import resolve, service_type, topic_to_dds, type_to_dds
from rostool.graph.ros2.protocol import Ros2Verbs
from rostool.graph.ros2.types import TypeSupport, gid_size
from rostool.graph.ros2_calls import ServiceEndpoint, service_info_facts
from rostool.interfaces.ros2_types import distro_from_env

if TYPE_CHECKING:
    from rostool.graph.recording import Encoding
    from rostool.graph.ros2.services import ServiceClient
    from rostool.graph.ros2.type_description import TypeDescriptionServer

SETTLE_MAX_SECONDS = 3.0  # listing verbs: how long an empty graph is given before "no participants"
NODES_MAX_SECONDS = 4.5  # node verbs: Fast DDS sends ros_discovery_info on its 3 s heartbeat
TOPIC_WAIT_SECONDS = 1.5
NODE_WAIT_SECONDS = NODES_MAX_SECONDS  # unknown types: how long to wait for the publishers' nodes
READER_CACHE_DEPTH = 1000  # echo/hz/pub: how long to look for a topic before warning it is not there yet
_ANY_SAMPLE = 0x7F  # SampleState.Any | ViewState.Any | InstanceState.Any (DDS mask bits)


class Session:
    """One DDS participant with rmw_dds_common's graph machinery."""

    def __init__(self, node_name: str, types: TypeSupport) -> None:
        from cyclonedds.core import Policy, Qos
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        self.types = types
        self.participant = dds.Participant()
        self.node = NodeEntry("/", node_name)
        self._lock = threading.RLock()
        self._topics: dict[str, Any] = {}
        self._keep: list[Any] = []
        info_cls = types.idl_class(DISCOVERY_TYPE)
        info_topic: Any = Topic(self.participant.dp, DISCOVERY_TOPIC, info_cls)
        user_data = types.user_data(DISCOVERY_TYPE)
        graph_qos = dds.QosProfile("reliable", "transient_local", 1)
        writer_qos = dds.to_dds_qos(graph_qos, user_data)
        reader_qos = dds.to_dds_qos(dds.QosProfile("reliable", "transient_local", 0), user_data)
        self._info_writer = DataWriter(self.participant.dp, info_topic, qos=writer_qos)
        self._info_reader = DataReader(
            self.participant.dp, info_topic, qos=Qos(*reader_qos.policies, Policy.IgnoreLocal.Participant)
        )
        self.cache = GraphCache(self.participant, self._info_reader)
        self.announce()

    def announce(self) -> None:
        from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]

        payload = encode_entities_info(self.participant.guid, [self.node], gid_size(self.types.distro))
        ddspy_write(self._info_writer._ref, payload)

    def topic(self, dds_name: str, store_name: str, request_header: bool = False) -> Any:
        from cyclonedds.core import DDSException
        from cyclonedds.topic import Topic

        with self._lock:
            found = self._topics.get(dds_name)
            if found is not None:
                if found[1] != store_name:
                    raise RostoolError(f"this process already uses {dds_name} with type {found[1]}")
                return found[0]
            try:
                data_type = self.types.idl_class(store_name, request_header)
                created: Any = Topic(self.participant.dp, dds_name, data_type)
            except DDSException as err:
                where = f"{dds_name} ({type_to_dds(store_name)})"
                raise RostoolError(f"cannot create DDS topic {where}: {err}") from err
            self._topics[dds_name] = (created, store_name)
            return created

    def writer(
        self, dds_name: str, store_name: str, profile: dds.QosProfile, request_header: bool = False
    ) -> Any:
        from cyclonedds.pub import DataWriter

        return self._announced(DataWriter, self.node.writers, dds_name, store_name, profile, request_header)

    def reader(
        self, dds_name: str, store_name: str, profile: dds.QosProfile, request_header: bool = False
    ) -> Any:
        from cyclonedds.sub import DataReader

        return self._announced(DataReader, self.node.readers, dds_name, store_name, profile, request_header)

    def _announced(
        self,
        kind: Any,
        announced: list[bytes],
        dds_name: str,
        store_name: str,
        profile: dds.QosProfile,
        request_header: bool,
    ) -> Any:
        """A DDS reader or writer with the type hash in USER_DATA, listed on ros_discovery_info."""
        endpoint = kind(
            self.participant.dp, self.topic(dds_name, store_name, request_header),
            qos=dds.to_dds_qos(profile, self.types.user_data(store_name)),
        )  # fmt: skip
        with self._lock:
            announced.append(endpoint.guid.bytes)
            self.announce()
        return endpoint

    def used_types(self) -> set[str]:
        """The message types of this session's topics (service topics give their request/reply types)."""
        with self._lock:
            return {store_name for _topic, store_name in self._topics.values()}

    def drop(self, endpoint: Any) -> None:
        """Delete a reader or writer this session made and stop announcing it."""
        with self._lock:
            guid = endpoint.guid.bytes
            for announced in (self.node.readers, self.node.writers):
                if guid in announced:
                    announced.remove(guid)
                    self.announce()
        endpoint.__del__()  # cyclonedds deletes an entity only this way (or with its participant)

    def close(self) -> None:
        """Leave the graph at once: first say on ros_discovery_info that this participant has no node left
        (rmw's graph caches drop the node on that sample, as when a node is destroyed, where the
        participant's disposal alone may only be noticed when its lease expires), then delete it."""
        from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]

        with self._lock:
            payload = encode_entities_info(self.participant.guid, [], gid_size(self.types.distro))
            with contextlib.suppress(Exception):
                ddspy_write(self._info_writer._ref, payload)
                self._info_writer.wait_for_acks(dds_duration_ms(200))
        self.participant.close()


def dds_duration_ms(milliseconds: int) -> int:
    from cyclonedds.util import duration

    return int(duration(milliseconds=milliseconds))


class Ros2Graph(Ros2Verbs):
    """Read-only verbs wait for discovery to settle; subscribing and publishing add DDS endpoints."""

    ros_version = 2
    style: Literal["ros1", "ros2"] = "ros2"
    encoding: Encoding = "cdr"

    def __init__(
        self,
        node_name: str = "rostool",
        distro: str | None = None,
        anonymous: bool = True,
        interface_paths: Sequence[str] = (),
    ) -> None:
        dds.domain_id()  # a bad ROS_DOMAIN_ID fails before anything starts
        dds.discovery_range()
        self.interface_paths = tuple(interface_paths)
        self.types = TypeSupport(distro or distro_from_env(), self.interface_paths)
        self.qos_request = dds.QosRequest()
        self.warn: Callable[[str], None] = lambda text: print(f"WARNING: {text}", file=sys.stderr)
        base = node_name.strip("/")
        self._node_name = f"{base}_{os.getpid()}" if anonymous else base
        self._session: Session | None = None
        self._lock = threading.Lock()
        self._subscriptions: list[_Subscription] = []
        self._type_server: TypeDescriptionServer | None = None
        self._learn_lock = threading.Lock()  # one fetch per type when several subscriptions meet it
        self.require_peers = True  # False: an empty graph lists nothing instead of failing (the daemon)

    @property
    def session(self) -> Session:
        with self._lock:
            if self._session is None:
                self._session = Session(self._node_name, self.types)
            return self._session

    @property
    def node_name(self) -> str:
        return "/" + self._node_name

    def __enter__(self) -> Ros2Graph:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def close(self) -> None:
        for sub in self._subscriptions:
            sub.close()
        self._subscriptions.clear()
        if self._type_server is not None:
            self._type_server.close()
            self._type_server = None
        if self._session is not None:
            self._session.close()
            self._session = None

    def resolve(self, name: str) -> str:
        return resolve(name)

    # --- discovery ----------------------------------------------------------------------------
    def _settled(self, require_peers: bool, nodes: bool = False) -> GraphCache:
        cache = self.session.cache
        found = cache.settle(maximum=NODES_MAX_SECONDS if nodes else SETTLE_MAX_SECONDS, nodes=nodes)
        if require_peers and self.require_peers and not found:
            participant = self.session.participant
            raise RostoolError(
                f"no ROS 2 participants found on domain {participant.domain_id} within "
                f"{SETTLE_MAX_SECONDS:g} s ({participant.range} discovery): is anything running with this "
                "ROS_DOMAIN_ID? Nodes on other machines need ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET"
            )
        return cache

    def wait_for_discovery(self) -> None:
        """Let discovery settle once: a long-lived graph (the daemon's) then answers at once."""
        cache = self.session.cache
        cache.settle(maximum=NODES_MAX_SECONDS, nodes=True)
        cache.long_lived = True

    def wait_for_newcomers(self, limit: float = 1.0) -> None:
        """Fold in what discovery brought, waiting (at most `limit`) for participants that appeared a
        moment ago to describe their endpoints and nodes."""
        self.session.cache.await_described(limit)

    def _owners(self, cache: GraphCache) -> dict[bytes, str]:
        return cache.node_of()

    # --- nodes --------------------------------------------------------------------------------
    def node_names(self) -> list[str]:
        cache = self._settled(require_peers=True, nodes=True)
        return sorted(node.full_name for node in cache.node_entries())  # a name twice: two nodes, as in ros2

    def node_uri(self, name: str) -> str:
        cache = self._settled(require_peers=True, nodes=True)
        resolved = resolve(name)
        with cache._lock:
            for participant, nodes in cache.nodes.items():
                if participant in cache.participants and any(n.full_name == resolved for n in nodes):
                    return "dds:" + participant.hex()
        raise RostoolError(f"unknown node {resolved}: no ROS 2 participant announces it")

    def node_info(self, name: str) -> NodeInfo:
        resolved = resolve(name)
        uri = self.node_uri(resolved)
        cache = self.session.cache
        owners = self._owners(cache)
        pubs: set[tuple[str, str]] = set()
        subs: set[tuple[str, str]] = set()
        servers: set[tuple[str, str]] = set()
        clients: set[tuple[str, str]] = set()
        for endpoint in cache.remote_endpoints():
            ros = endpoint.ros
            if ros is None or owners.get(endpoint.guid) != resolved:
                continue
            kind, ros_name = ros
            if kind == "topic":
                (pubs if endpoint.is_writer else subs).add((ros_name, endpoint.type_name))
            elif kind == "request":
                target = clients if endpoint.is_writer else servers
                target.add((ros_name, service_type(endpoint.type_name)))
        info = NodeInfo(resolved, uri, None, sorted(pubs), sorted(subs), sorted(s for s, _ in servers), [])
        info.service_types = dict(servers)
        info.service_clients = sorted(clients)
        return info

    def ping(self, name: str) -> float:
        raise RostoolError("ROS 2 nodes cannot be pinged (there is no node API); try `rostool node info`")

    def kill(self, name: str) -> None:
        raise RostoolError("ROS 2 nodes cannot be killed remotely (there is no node API); stop the process")

    # --- topics -------------------------------------------------------------------------------
    def topics(self) -> list[TopicInfo]:
        cache = self._settled(require_peers=True)
        owners = self._owners(cache)
        found: dict[str, TopicInfo] = {}
        for endpoint in sorted(cache.remote_endpoints(), key=lambda e: not e.is_writer):
            ros = endpoint.ros
            if ros is None or ros[0] != "topic":
                continue
            info = found.setdefault(ros[1], TopicInfo(ros[1], endpoint.type_name))
            node = owners.get(endpoint.guid, UNKNOWN_NODE)
            (info.publishers if endpoint.is_writer else info.subscribers).append(node)
        for info in found.values():
            info.publishers.sort()
            info.subscribers.sort()
        return [found[name] for name in sorted(found)]

    def topic_endpoints(self, name: str) -> list[dict[str, Any]]:
        """Every remote reader and writer of a topic with its node, type, GID and QoS (topic info -v)."""
        resolved = resolve(name)
        cache = self._settled(require_peers=True, nodes=True)
        owners = self._owners(cache)
        rows = []
        for endpoint in cache.remote_endpoints():
            if endpoint.ros != ("topic", resolved):
                continue
            node = owners.get(endpoint.guid, UNKNOWN_NODE)
            rows.append({
                "node": node, "endpoint_type": "PUBLISHER" if endpoint.is_writer else "SUBSCRIPTION",
                "type": endpoint.type_name, "type_hash": endpoint.type_hash, "gid": endpoint.guid.hex("."),
                "qos": vars(endpoint.qos).copy(),
            })  # fmt: skip
        return sorted(rows, key=lambda r: (r["endpoint_type"] != "PUBLISHER", r["node"]))

    def topic_type(self, name: str) -> str | None:
        resolved = resolve(name)
        cache = self.session.cache
        cache.settle(maximum=TOPIC_WAIT_SECONDS)
        endpoints = [e for e in cache.remote_endpoints() if e.ros == ("topic", resolved)]
        endpoints.sort(key=lambda e: not e.is_writer)
        return endpoints[0].type_name if endpoints else None

    def subscribe(
        self,
        topic: str,
        on_message: Callable[[Received], None],
        on_error: Callable[[str], None] | None = None,
    ) -> Subscription:
        _ = self.session  # started here, not in the subscription thread
        sub = _Subscription(self, resolve(topic), on_message, on_error or self.warn)
        self._subscriptions.append(sub)
        return sub

    def publisher(self, topic: str, type_name: str, latch: bool = False) -> _Publisher:
        resolved = resolve(topic)
        store_name = self.types.store_name(type_name)
        existing = self.topic_type(resolved)
        if existing and existing != store_name:
            raise RostoolError(
                f"topic {resolved} already has type {existing}; cannot publish {store_name} on it"
            )
        request = self.qos_request
        base = request.base()
        if latch and request.durability is None:
            base = dds.QosProfile(base.reliability, "transient_local", base.depth)
        profile = request.apply(base)
        writer = self.session.writer(topic_to_dds(resolved), store_name, profile)
        self._serve_type_descriptions()
        return _Publisher(resolved, store_name, writer, self.types)

    def _serve_type_descriptions(self) -> None:
        """Publishing processes answer `<node>/get_type_description` as Iron+ nodes do, so subscribers
        without our interface sources can still decode what we publish."""
        from rostool.graph.ros2 import type_description

        with self._lock:
            if self._type_server is not None or not type_description.available(self.types):
                return
        server = type_description.TypeDescriptionServer(self.session, self.node_name)
        with self._lock:
            if self._type_server is None:
                self._type_server = server
                return
        server.close()  # another thread started one first

    def learn_type(self, type_name: str, publishers: Sequence[Endpoint]) -> None:
        """Make an unknown topic type known from its publishers' type description services, or raise the
        unknown-type error saying why that failed."""
        from rostool.graph.ros2 import type_description

        with self._learn_lock:
            if self.types.knows(type_name):
                return
            if type_description.available(self.types):
                owners = self.session.cache.node_of()
                asked = [
                    (owners[e.guid], e.type_hash)
                    for e in publishers
                    if e.guid in owners and e.type_name == type_name
                ]
                why = type_description.fetch_types(self.session, type_name, asked)
                if why is None:
                    return
            else:
                why = f"type descriptions exist from Iron on, and the distro is {self.types.distro}"
            try:
                self.types.store_name(type_name)
            except RostoolError as err:
                text = f"{err}. The publisher did not provide its type description ({why})"
                raise RostoolError(text) from None

    # --- services -----------------------------------------------------------------------------
    def services(self) -> list[tuple[str, str, list[str]]]:
        """(name, type, server nodes) of every service: a server reads `rq/<name>Request`."""
        cache = self._settled(require_peers=True)
        owners = self._owners(cache)
        found: dict[str, tuple[str, list[str]]] = {}
        for endpoint in cache.remote_endpoints():
            ros = endpoint.ros
            if ros is None or ros[0] != "request" or endpoint.is_writer:
                continue
            entry = found.setdefault(ros[1], (service_type(endpoint.type_name), []))
            entry[1].append(owners.get(endpoint.guid, UNKNOWN_NODE))
        return [(name, found[name][0], sorted(found[name][1])) for name in sorted(found)]

    def service_endpoints(self, nodes: bool = False) -> list[tuple[str, str, list[str], list[str]]]:
        """(name, type, server nodes, client nodes) of every service that has a server; with `nodes`,
        once every participant has named its nodes."""
        cache = self._settled(require_peers=True, nodes=nodes)
        owners = self._owners(cache)
        found: dict[str, tuple[str, set[str], set[str]]] = {}
        for endpoint in cache.remote_endpoints():
            ros = endpoint.ros
            if ros is None or ros[0] != "request":
                continue
            entry = found.setdefault(ros[1], ("", set(), set()))
            node = owners.get(endpoint.guid, UNKNOWN_NODE)
            if endpoint.is_writer:
                entry[2].add(node)
            else:
                found[ros[1]] = (service_type(endpoint.type_name), entry[1] | {node}, entry[2])
        return [
            (name, type_, sorted(servers), sorted(clients))
            for name, (type_, servers, clients) in sorted(found.items())
            if servers
        ]

    def service_info(self, service: str) -> dict[str, Any] | None:
        """ros2 service info's facts: the service's types, its clients and its servers (each with node, type
        hash, the GIDs and QoS of its two DDS endpoints); None when no client or server announces it."""
        resolved = resolve(service)
        cache = self._settled(require_peers=True, nodes=True)
        owners = self._owners(cache)
        endpoints = (
            ServiceEndpoint(
                kind=ros[0], node=owners.get(endpoint.guid, UNKNOWN_NODE), is_writer=endpoint.is_writer,
                service_type=service_type(endpoint.type_name), type_hash=endpoint.type_hash,
                gid=endpoint.guid.hex("."), qos=vars(endpoint.qos),
            )
            for endpoint in cache.remote_endpoints()
            if (ros := endpoint.ros) is not None and ros[1] == resolved and ros[0] in ("request", "reply")
        )  # fmt: skip
        return service_info_facts(resolved, endpoints)

    def find_service_type(self, service: str) -> str | None:
        """The type a server of `service` announces (`pkg/srv/Name`), None when no server is seen."""
        resolved = resolve(service)
        return next((type_ for name, type_, _nodes in self.services() if name == resolved), None)

    def service_client(self, service: str, srv_type: str) -> ServiceClient:
        from rostool.graph.ros2.services import ServiceClient

        return ServiceClient(self.session, resolve(service), srv_type)

    def call_service(self, service: str, srv_type: str, request: Any, timeout: float = 5.0) -> Any:
        """Call a service (rmw_cyclonedds_cpp's request/reply convention) with a request mapping."""
        client = self.service_client(service, srv_type)
        message = self.build_message(client.request_type, request)
        return client.call(message, timeout)

    def message_class(self, type_name: str) -> type:
        return self.types.store.types[self.types.store_name(type_name)]  # type: ignore[no-any-return]

    def build_message(self, type_name: str, value: Any) -> Any:
        from rostool.interfaces.fill import build_message

        store_name = self.types.store_name(type_name)
        return build_message(self.types.store, store_name, self.types.with_defaults(store_name, value))


class _Publisher:
    def __init__(self, topic: str, store_name: str, writer: Any, types: TypeSupport) -> None:
        self.topic = topic
        self.type_name = store_name
        self._writer = writer
        self._ref = writer._ref
        self._types = types

    def publish(self, message: object) -> None:
        self.publish_raw(self._types.serialize(message, self.type_name))

    def publish_raw(self, payload: bytes) -> None:
        """Write CDR bytes (with their 4-byte encapsulation header) as they are."""
        from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]

        result = ddspy_write(self._ref, payload)
        if result < 0:
            raise RostoolError(f"DDS write on {self.topic} failed (code {result})")

    def wait_for_subscribers(self, count: int, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while self.subscriber_count < count:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    @property
    def subscriber_count(self) -> int:
        return int(self._writer.get_publication_matched_status().current_count)


class _Subscription:
    """Waits (in its own thread) for the topic's type to be known, then reads raw samples as they come."""

    def __init__(
        self,
        graph: Ros2Graph,
        topic: str,
        on_message: Callable[[Received], None],
        on_error: Callable[[str], None],
    ) -> None:
        self._graph = graph
        self._topic = topic
        self._on_message = on_message
        self._on_error = on_error
        self._closed = threading.Event()
        self._waitset: Any = None
        self._thread = threading.Thread(target=self._run, name=f"ros2 sub {topic}", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._closed.set()
        waitset = self._waitset
        if waitset is not None:
            waitset.set_trigger(True)
        if threading.current_thread() is not self._thread:
            self._thread.join(2.0)

    def _run(self) -> None:
        try:
            chosen = self._wait_for_type()
            if chosen is not None:
                self._read(*chosen)
        except RostoolError as err:
            self._on_error(str(err))

    def _publishers(self) -> list[Endpoint]:
        cache = self._graph.session.cache
        cache.poll()
        return [e for e in cache.remote_endpoints() if e.ros == ("topic", self._topic)]

    def _described_publishers(self, writers: list[Endpoint]) -> list[Endpoint]:
        """The writers, once their nodes are known: ros_discovery_info may come a moment after them."""
        cache = self._graph.session.cache
        deadline = time.monotonic() + NODE_WAIT_SECONDS
        while writers and not self._closed.is_set() and time.monotonic() < deadline:
            owners = cache.node_of()
            if all(w.guid in owners for w in writers):
                break
            self._closed.wait(0.05)
            cache.poll()
        return writers

    def _wait_for_type(self) -> tuple[str, dds.QosProfile] | None:
        graph = self._graph
        cache = graph.session.cache
        while not self._closed.is_set():
            endpoints = self._publishers()
            writers = [e for e in endpoints if e.is_writer]
            known = writers or endpoints
            settled = time.monotonic() - cache.started >= 0.5
            if known and (writers or settled):
                type_name = known[0].type_name
                if not graph.types.knows(type_name):
                    graph.learn_type(type_name, self._described_publishers(writers))
                profile, notes = dds.adapt_to_publishers(graph.qos_request, [w.qos for w in writers])
                for note in notes:
                    graph.warn(note)
                return type_name, profile
            self._closed.wait(0.05)
        return None

    def _read(self, store_name: str, profile: dds.QosProfile) -> None:
        """Read until closed; when a publisher appears that the reader cannot match and the user left the
        QoS to rostool, subscribe again with the QoS adapted to all the publishers now known."""
        next_profile: dds.QosProfile | None = profile
        while next_profile is not None and not self._closed.is_set():
            next_profile = self._read_with(store_name, next_profile)

    def _read_with(self, store_name: str, profile: dds.QosProfile) -> dds.QosProfile | None:
        from cyclonedds._clayer import ddspy_take  # type: ignore[import-not-found]
        from cyclonedds.core import ReadCondition, WaitSet
        from cyclonedds.util import duration

        graph = self._graph
        cache_profile = profile
        if graph.qos_request.depth is None and profile.depth:
            # A reader's depth is local (it never affects matching): a deep cache lets a busy moment pass
            # without losing samples a reliable publisher already delivered.
            cache_profile = replace(profile, depth=max(profile.depth, READER_CACHE_DEPTH))
        reader = graph.session.reader(topic_to_dds(self._topic), store_name, cache_profile)
        waitset = WaitSet(graph.session.participant.dp)
        waitset.attach(ReadCondition(reader, _ANY_SAMPLE))
        self._waitset = waitset
        types, topic, deliver, clock = graph.types, self._topic, self._on_message, time.time_ns
        store = types.store

        def decode(payload: bytes) -> Any:
            return store.deserialize_cdr(payload, store_name)

        ref = reader._ref
        reported = 0
        next_check = 0.0
        while not self._closed.is_set():
            waitset.wait(duration(milliseconds=250))
            while True:
                samples = ddspy_take(ref, _ANY_SAMPLE, 512)
                if isinstance(samples, int) or not samples:
                    break
                for data, info in samples:
                    if info.valid_data:
                        deliver(Received(topic, data, clock(), store_name, decode))
            now = time.monotonic()
            if now >= next_check:
                next_check = now + 0.5
                status = reader.get_requested_incompatible_qos_status()
                if status.total_count > reported:
                    reported = status.total_count
                    adapted = self._readapted(profile)
                    if adapted is not None:
                        graph.session.drop(reader)
                        return adapted
                    self._report_incompatible(status.last_policy_id, profile)
        return None

    def _readapted(self, profile: dds.QosProfile) -> dds.QosProfile | None:
        """The QoS that serves every publisher now known, when it differs from `profile`."""
        offered = [w.qos for w in self._publishers() if w.is_writer]
        if not offered:
            return None
        adapted, notes = dds.adapt_to_publishers(self._graph.qos_request, offered)
        if adapted.reliability == profile.reliability and adapted.durability == profile.durability:
            return None  # the user's own --qos-* choice, or nothing better to do
        for note in notes:
            self._graph.warn(note)
        return adapted

    def _report_incompatible(self, policy_id: int, profile: dds.QosProfile) -> None:
        """Fatal when no known publisher can serve this reader; otherwise a warning, as ros2 topic echo
        gives, and the compatible publishers keep being read."""
        policy = dds.POLICY_NAMES.get(policy_id, f"policy {policy_id}")
        offered = [w.qos for w in self._publishers() if w.is_writer]
        described = sorted({qos.describe() for qos in offered})
        offers = f"; publishers offer {'; '.join(described)}" if described else ""
        text = (
            f"a publisher of {self._topic} offers QoS incompatible with this subscription "
            f"({profile.describe()}): incompatible policy {policy}{offers}"
        )
        if offered and not any(dds.serves(qos, profile) for qos in offered):
            self._on_error(f"{text} (adjust --qos-reliability / --qos-durability)")
        else:
            self._graph.warn(f"{text}; no messages will be received from it")
