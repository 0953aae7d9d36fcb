"""The ROS 2 graph (ros2_base) over rostool's own DDS: topics, nodes and QoS the way rmw_cyclonedds_cpp puts
them on the wire; this module is the transport only (endpoints from discovery's cache, raw DDS readers and
writers, service clients).

The DDS participant (session.py) starts on first need. It announces one node, `/rostool_<pid>`, on
ros_discovery_info (so ROS 2 tools list it like any node) with the readers and writers it creates. Samples
are moved as raw CDR bytes (`ddspy_write` / `ddspy_take`, the calls cyclonedds' own DataWriter/DataReader
make after serializing), so what goes out and what comes in is exactly rosbags' CDR, byte for byte.

A process that publishes also serves `<node>/get_type_description` (REP 2016), and a subscription to a type
rostool does not know asks the publisher's node for it (type_description.py).
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.ros2.dds import POLICY_NAMES
from rostool.graph.ros2.discovery import Endpoint, GraphCache
from rostool.graph.ros2.session import Session
from rostool.graph.ros2.types import TypeSupport
from rostool.graph.ros2_base.env import discovery_range
from rostool.graph.ros2_base.graph import NodeEndpoints, Ros2Base
from rostool.graph.ros2_base.names import UNKNOWN_NODE, request_topic, resolve, service_type, topic_to_dds
from rostool.graph.ros2_base.subscription import REJOIN_POLL, DrainingSubscription
from rostool.graph.ros2_base.transport import EndpointView, ServiceEndpoint
from rostool.interfaces.ros2_types import distro_from_env

if TYPE_CHECKING:
    from rostool.graph.base import GoalOutcome, GoalWatcher, OnError, OnMessage, Subscription
    from rostool.graph.ros2.services import ServiceClient, ServiceServer
    from rostool.graph.ros2.type_description import TypeDescriptionServer
    from rostool.graph.ros2_base.qos import QosProfile, QosRequest
    from rostool.graph.ros2_base.transport import Writer

SETTLE_MAX_SECONDS = 3.0  # listing verbs: how long an empty graph is given before "no participants"
NODES_MAX_SECONDS = 4.5  # node verbs: Fast DDS sends ros_discovery_info on its 3 s heartbeat
TOPIC_WAIT_SECONDS = 1.5
NODE_WAIT_SECONDS = NODES_MAX_SECONDS  # unknown types: how long to wait for the publishers' nodes
_ANY_SAMPLE = 0x7F  # SampleState.Any | ViewState.Any | InstanceState.Any (DDS mask bits)


class Ros2Graph(Ros2Base):
    """The transport is one DDS participant (`Session`), started on first need, or `discovery`'s, started
    before this module was even imported (backends.py)."""

    def __init__(self, *args: Any, discovery: GraphCache | None = None, **kwargs: Any) -> None:
        self._discovery = discovery
        super().__init__(*args, **kwargs)

    def _prepare(self, distro: str | None) -> None:
        discovery_range()
        self.spin_time: float | None = None  # --spin-time: a listing's discovery wait, as ros2cli's
        self.types = TypeSupport(distro or distro_from_env(), self.interface_paths)
        self._session: Session | None = None
        self._type_server: TypeDescriptionServer | None = None
        self._learn_lock = threading.Lock()  # one fetch per type when several subscriptions meet it

    @property
    def session(self) -> Session:
        with self._lock:
            if self._session is None:
                self._session = Session(self._node_name, self.types, self._discovery)
            return self._session

    def _start(self) -> None:
        _ = self.session

    def _close_transport(self) -> None:
        if self._type_server is not None:
            self._type_server.close()
            self._type_server = None
        if self._session is not None:
            self._session.close()
            self._session = None
        elif self._discovery is not None:
            self._discovery.participant.close()
        self._discovery = None

    # --- discovery ----------------------------------------------------------------------------
    def _settled(self, require_peers: bool, nodes: bool = False) -> GraphCache:
        cache = self.session.cache
        window = SETTLE_MAX_SECONDS
        if self.spin_time is not None:
            window = self.spin_time
            found = cache.spin(self.spin_time)
        else:
            found = cache.settle(maximum=NODES_MAX_SECONDS if nodes else SETTLE_MAX_SECONDS, nodes=nodes)
        if require_peers and self.require_peers and not found:
            participant = self.session.participant
            from rostool.graph.ros2_base.doctor import empty_listing_hint

            hint = empty_listing_hint(participant.domain_id, participant.range) or (
                ": is anything running with this ROS_DOMAIN_ID? `rostool doctor` checks the network"
            )
            raise RostoolError(
                f"no ROS 2 participants found on domain {participant.domain_id} within "
                f"{window:g} s ({participant.range} discovery){hint}"
            )
        return cache

    def _listing(self, nodes: bool = False) -> None:
        self._settled(require_peers=True, nodes=nodes)

    def wait_for_discovery(self) -> None:
        """Let discovery settle once: a long-lived graph (the daemon's) then answers at once."""
        cache = self.session.cache
        cache.settle(maximum=NODES_MAX_SECONDS, nodes=True)
        cache.long_lived = True

    def wait_for_newcomers(self, limit: float = 1.0, ignore: bytes | None = None) -> None:
        """Fold in what discovery brought, waiting (at most `limit`) for participants that appeared a
        moment ago to describe their endpoints and nodes, but `ignore` (the asking client's)."""
        self.session.cache.await_described(limit, ignore=ignore)

    @property
    def participant_guid(self) -> bytes | None:
        """This process's DDS participant, once started (the daemon does not wait for it to describe
        itself)."""
        if self._session is not None:
            return self._session.participant.guid
        return self._discovery.participant.guid if self._discovery is not None else None

    def _view(self, endpoint: Endpoint, owners: dict[bytes, str]) -> EndpointView:
        return EndpointView(
            owners.get(endpoint.guid, UNKNOWN_NODE), endpoint.is_writer, endpoint.type_name,
            endpoint.type_hash, endpoint.guid.hex("."), endpoint.qos,
        )  # fmt: skip

    def _all_topic_views(self) -> Iterable[tuple[str, EndpointView]]:
        cache = self.session.cache
        owners = cache.node_of()
        for endpoint in sorted(cache.remote_endpoints(), key=lambda e: not e.is_writer):
            ros = endpoint.ros
            if ros is not None and ros[0] == "topic":
                yield ros[1], self._view(endpoint, owners)

    def topic_views(self, topic: str) -> list[EndpointView]:
        cache = self.session.cache
        cache.poll()
        owners = cache.node_of()
        endpoints = [e for e in cache.remote_endpoints() if e.ros == ("topic", topic)]
        return [self._view(e, owners) for e in sorted(endpoints, key=lambda e: not e.is_writer)]

    def _await_topic(self, topic: str) -> None:
        self.session.cache.settle(maximum=TOPIC_WAIT_SECONDS)

    def published_topics(self) -> set[str]:
        cache = self.session.cache
        cache.poll()
        writers = [e.ros for e in cache.remote_endpoints() if e.is_writer]
        return {ros[1] for ros in writers if ros is not None and ros[0] == "topic"}

    # --- nodes --------------------------------------------------------------------------------
    def node_names(self) -> list[str]:
        self._listing(nodes=True)
        return sorted(node.full_name for node in self.session.cache.node_entries())  # a name twice: two nodes

    def node_uri(self, name: str) -> str:
        cache = self._settled(require_peers=True, nodes=True)
        resolved = resolve(name)
        with cache._lock:
            for participant, nodes in cache.nodes.items():
                if participant in cache.participants and any(n.full_name == resolved for n in nodes):
                    return "dds:" + participant.hex()
        raise RostoolError(f"unknown node {resolved}: no ROS 2 participant announces it")

    def _node_endpoints(self, node: str) -> NodeEndpoints:
        cache = self.session.cache
        owners = cache.node_of()
        pubs: set[tuple[str, str]] = set()
        subs: set[tuple[str, str]] = set()
        servers: set[tuple[str, str]] = set()
        clients: set[tuple[str, str]] = set()
        for endpoint in cache.remote_endpoints():
            ros = endpoint.ros
            if ros is None or owners.get(endpoint.guid) != node:
                continue
            kind, ros_name = ros
            if kind == "topic":
                (pubs if endpoint.is_writer else subs).add((ros_name, endpoint.type_name))
            elif kind == "request":
                target = clients if endpoint.is_writer else servers
                target.add((ros_name, service_type(endpoint.type_name)))
        return pubs, subs, servers, clients

    def before_node_check(self) -> None:
        """Nothing to wait for: service endpoints are polled as they come."""

    def serves_under(self, prefix: str) -> bool:
        cache = self.session.cache
        dds_prefix = request_topic(prefix).removesuffix("Request")
        cache.poll()
        return any(e.dds_topic.startswith(dds_prefix) and not e.is_writer for e in cache.remote_endpoints())

    def announces_node(self, node: str) -> bool:
        return any(entry.full_name == node for entry in self.session.cache.node_entries())

    # --- topics -------------------------------------------------------------------------------
    def _subscription(
        self, topic: str, on_message: OnMessage, on_error: OnError,
        request: QosRequest | None = None, warn: Callable[[str], None] | None = None,
        type_name: str | None = None,
    ) -> Subscription:  # fmt: skip
        return DdsSubscription(self, topic, on_message, on_error, request, warn, type_name)

    def store_name(self, type_name: str) -> str:
        return self.types.store_name(type_name)

    def _writer(self, topic: str, store_name: str, profile: QosProfile) -> Writer:
        writer = DdsWriter(topic, self.session.writer(topic_to_dds(topic), store_name, profile))
        self._serve_type_descriptions()
        return writer

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
    def service_endpoints(self, nodes: bool = False) -> list[tuple[str, str, list[str], list[str]]]:
        cache = self._settled(require_peers=True, nodes=nodes)
        owners = cache.node_of()
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

    def _service_endpoint_views(self, service: str) -> Iterable[ServiceEndpoint]:
        cache = self.session.cache
        owners = cache.node_of()
        return (
            ServiceEndpoint(
                kind=ros[0], node=owners.get(endpoint.guid, UNKNOWN_NODE), is_writer=endpoint.is_writer,
                service_type=service_type(endpoint.type_name), type_hash=endpoint.type_hash,
                gid=endpoint.guid.hex("."), qos=vars(endpoint.qos),
            )
            for endpoint in cache.remote_endpoints()
            if (ros := endpoint.ros) is not None and ros[1] == service and ros[0] in ("request", "reply")
        )  # fmt: skip

    def service_client(self, service: str, srv_type: str) -> ServiceClient:
        from rostool.graph.ros2.services import ServiceClient

        return ServiceClient(self.session, resolve(service), srv_type)

    def _service_server(self, service: str, srv_type: str, answer: Callable[[Any], Any]) -> ServiceServer:
        from rostool.graph.ros2.services import ServiceServer

        return ServiceServer(self.session, service, srv_type, answer)

    def call_service(self, service: str, srv_type: str, request: Any, timeout: float = 5.0) -> Any:
        """Call a service (rmw_cyclonedds_cpp's request/reply convention) with a request mapping."""
        client = self.service_client(service, srv_type)
        message = self.build_message(client.request_type, request)
        return client.call(message, timeout)

    # --- actions ------------------------------------------------------------------------------
    def send_goal(
        self, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> GoalOutcome:
        from rostool.graph.ros2.actions import send_goal

        return send_goal(self, self.session, name, kind, goal, timeout, watcher)


class DdsWriter:
    """A DDS writer that takes CDR bytes (with their 4-byte encapsulation header) as they are."""

    def __init__(self, topic: str, writer: Any) -> None:
        self.topic = topic
        self._writer = writer
        self._ref = writer._ref

    def write(self, payload: bytes) -> None:
        from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]

        result = ddspy_write(self._ref, payload)
        if result < 0:
            raise RostoolError(f"DDS write on {self.topic} failed (code {result})")

    def matched(self) -> int:
        return int(self._writer.get_publication_matched_status().current_count)


class DdsSubscription(DrainingSubscription):
    """Reads raw samples through a DDS wait set; a type rostool does not know is asked of the publishers'
    nodes (type_description.py)."""

    _graph: Ros2Graph

    def _setup(self) -> None:
        self._waitset: Any = None
        self._reader: Any = None

    def _discovery_started(self) -> float:
        return self._graph.session.cache.started

    def _wake(self) -> None:
        # a guard condition: cyclonedds' WaitSet.set_trigger does not wake a wait in progress (the
        # reading thread then noticed the close only with its next sample or its 250 ms timeout)
        waitset = self._waitset
        if waitset is not None:
            waitset.wakeup.set(True)

    def _endpoints(self) -> list[EndpointView]:
        self._graph.session.cache.poll()
        return self._graph.topic_views(self._topic)

    def _known_type(self, type_name: str, writers: list[EndpointView]) -> str:
        graph = self._graph
        if not graph.types.knows(type_name):
            graph.learn_type(type_name, self._described_publishers())
        return type_name

    def _described_publishers(self) -> list[Endpoint]:
        """The writers, once their nodes are known: ros_discovery_info may come a moment after them."""
        cache = self._graph.session.cache
        writers = [e for e in cache.remote_endpoints() if e.ros == ("topic", self._topic) and e.is_writer]
        deadline = time.monotonic() + NODE_WAIT_SECONDS
        while writers and not self._closed.is_set() and time.monotonic() < deadline:
            owners = cache.node_of()
            if all(w.guid in owners for w in writers):
                break
            self._closed.wait(0.05)
            cache.poll()
        return writers

    def _drop(self) -> None:
        """Delete the reader and its wait set: a long-lived graph (the daemon's, relaying subscriptions)
        outlives its subscriptions, and cyclonedds deletes an entity only when told to."""
        waitset, self._waitset = self._waitset, None
        reader, self._reader = self._reader, None
        with contextlib.suppress(Exception):  # the participant is gone already: so are they
            if waitset is not None:
                wakeup = waitset.wakeup
                waitset.__del__()
                wakeup.__del__()
            if reader is not None:
                self._graph.session.drop(reader)

    def _matched_count(self) -> int | None:
        from cyclonedds.core import DDSException

        try:
            return int(self._reader.get_subscription_matched_status().current_count)
        except (AttributeError, DDSException):  # no reader (yet, or any more)
            return None

    def _read_with(self, store_name: str, profile: QosProfile) -> QosProfile | None:
        from cyclonedds._clayer import ddspy_take  # type: ignore[import-not-found]
        from cyclonedds.core import DDSStatus, ReadCondition
        from cyclonedds.util import duration

        from rostool.graph.ros2.dds import wakeable_waitset

        session = self._graph.session
        reader = session.reader(topic_to_dds(self._topic), store_name, self._cache_profile(profile))
        self._reader = reader
        waitset = wakeable_waitset(session.participant.dp)
        waitset.attach(ReadCondition(reader, _ANY_SAMPLE))
        self._waitset = waitset
        receive = self._receiver(store_name)
        ref = reader._ref
        reported = 0
        next_check = 0.0
        rejoin = self._rejoins()
        if rejoin:  # the first match wakes the wait (see DrainingSubscription._rejoins)
            reader.set_status_mask(DDSStatus.SubscriptionMatched)
            waitset.attach(reader)
        while not self._closed.is_set():
            waitset.wait(duration(milliseconds=round(REJOIN_POLL * 1000) if rejoin else 250))
            took = False
            while True:
                samples = ddspy_take(ref, _ANY_SAMPLE, 512)
                if isinstance(samples, int) or not samples:
                    break
                took = True
                for data, info in samples:
                    if info.valid_data:
                        receive(data)
            if rejoin and took:  # it takes messages: it stays, and its status no longer wakes the wait
                rejoin = False
                waitset.detach(reader)
            elif rejoin and (
                reader.get_subscription_matched_status().current_count > 0 or self._static_writer_known()
            ):
                self._rejoined = True
                self._reader = None
                session.drop(reader)
                return profile
            now = time.monotonic()
            if now >= next_check:
                next_check = now + 0.5
                status = reader.get_requested_incompatible_qos_status()
                if status.total_count > reported:
                    reported = status.total_count
                    adapted = self._readapted(profile)
                    if adapted is not None:
                        self._reader = None
                        session.drop(reader)
                        return adapted
                    policy_id = status.last_policy_id
                    self._report_incompatible(POLICY_NAMES.get(policy_id, f"policy {policy_id}"), profile)
        return None
