"""The ROS 2 graph (ros2_base) over rclpy, the transport only: the user's own client library and RMW see the
graph; rosbags makes and reads every message byte (subscriptions are raw, publishers publish serialized
bytes), so the verbs print exactly what they print with the DDS backend.

Listing verbs wait until the graph rmw reports stops changing (GRAPH_QUIET_SECONDS after something other
than this process was seen, at most SETTLE_MAX_SECONDS when nothing is), as discovery takes a moment.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.rclpy import types as rtypes
from rostool.graph.rclpy.host import type_hash
from rostool.graph.ros2_base.env import domain_id
from rostool.graph.ros2_base.graph import NodeEndpoints, Ros2Base
from rostool.graph.ros2_base.names import UNKNOWN_NODE, resolve
from rostool.graph.ros2_base.transport import EndpointView
from rostool.interfaces.names import hidden_name

if TYPE_CHECKING:
    from rostool.graph.base import GoalOutcome, GoalWatcher, OnError, OnMessage, Subscription
    from rostool.graph.rclpy.context import RclpyContext
    from rostool.graph.rclpy.services import RclpyServiceClient, RclpyServiceServer
    from rostool.graph.ros2_base.qos import QosProfile, QosRequest
    from rostool.graph.ros2_base.transport import ServiceEndpoint, Writer
    from rostool.interfaces.ros2_types import Ros2Types

GRAPH_QUIET_SECONDS = 0.5
# a direct listing (no daemon) answers no sooner than this: the participants that answer a newcomer's first
# announcements (and their endpoints) keep coming for a second or two, later on a loaded machine; the
# daemon's long-lived graph answers at once
SETTLE_MIN_SECONDS = 2.0
# Fast DDS: a participant may be heard only at its next periodic announcement (every 3 s), even after
# others answered at once (measured: one peer at 0.55 s, three at 2.85 s, a listing settled at 2.34 s missed
# them), so "quiet for a moment" proves nothing before one period has passed
FASTDDS_SETTLE_MIN_SECONDS = 3.3
# nothing but ourselves seen: how long before "no nodes found". A Fast DDS participant may answer a new one
# only with its next periodic announcement (every 3 s), so discovery takes from 0 to about 3 s
SETTLE_MAX_SECONDS = 4.5
TOPIC_WAIT_SECONDS = 1.5  # topic_type: how long a topic without publishers is given to get one


class RclpyGraph(Ros2Base):
    """The transport is one rclpy context and node (`context.py`), started on first need."""

    waits_long = True  # a direct listing waits SETTLE_MIN_SECONDS or more (its floor)

    def _prepare(self, distro: str | None) -> None:
        from rostool.graph.rclpy.facts import rclpy_distro
        from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS

        found = distro or rclpy_distro()[0]
        self._distro = found if found in DISTROS else DEFAULT_DISTRO
        self._types: Ros2Types | None = None
        self._context: RclpyContext | None = None
        self._settled = False
        self._long_lived = False  # the daemon's graph: settled once, then rmw keeps it current
        self._record_settled = False
        self.spin_time: float | None = None  # --spin-time: a listing's discovery wait, as ros2cli's
        self._spin_deadline: float | None = None
        self._described: set[str] = set()  # the long-lived graph's nodes seen with endpoints
        self._writers: list[RclpyWriter] = []

    @property
    def types(self) -> Ros2Types:  # type: ignore[override]
        """rosbags' store for the distro (made on first use: listing verbs never need it)."""
        if self._types is None:
            from rostool.interfaces.ros2_types import Ros2Types

            self._types = Ros2Types(self._distro, self.interface_paths)
        return self._types

    @property
    def context(self) -> RclpyContext:
        from rostool.graph.rclpy.context import RclpyContext

        with self._lock:
            if self._context is None:
                self._context = RclpyContext(self._node_name)
            return self._context

    @property
    def node(self) -> Any:
        return self.context.node

    @property
    def own_node(self) -> str:
        return self._node_name

    def _start(self) -> None:
        _ = self.context

    def _close_transport(self) -> None:
        if self._context is not None:
            _lingered(self._writers, LINGER_SECONDS)
            self._context.close()
            self._context = None

    # --- discovery ----------------------------------------------------------------------------
    def _snapshot(self) -> tuple[Any, ...]:
        node = self.node
        nodes = sorted(self.node_pairs())
        topics = sorted((n, tuple(t)) for n, t in node.get_topic_names_and_types())
        services = sorted((n, tuple(t)) for n, t in node.get_service_names_and_types())
        return nodes, topics, services

    def node_pairs(self) -> list[tuple[str, str]]:
        """(name, namespace) of every node but this process's own (and, in a long-lived graph, but those
        that left)."""
        own = (self._node_name, "/")
        pairs = [p for p in self.node.get_node_names_and_namespaces() if tuple(p) != own]
        return self._alive(pairs) if self._long_lived else pairs

    def _alive(self, pairs: list[tuple[str, str]]) -> list[tuple[str, str]]:
        """Without the nodes that had endpoints and lost every one: gone, though rmw's graph cache can keep
        the name of a node whose participant left for good (its last ros_discovery_info sample processed
        after the participant's removal: ros2/ros2#514), and a long-lived graph must never list it."""
        kept, listed = [], set()
        for name, namespace in pairs:
            full = self.full_name(name, namespace)
            listed.add(full)
            try:
                has_endpoints = any(self._node_endpoints(full))
            except RostoolError:
                has_endpoints = False
            if has_endpoints:
                self._described.add(full)
            elif full in self._described:
                continue
            kept.append((name, namespace))
        self._described &= listed  # forget the names rmw forgot
        return kept

    def settle(self, require_peers: bool = False, until: Callable[[], bool] | None = None) -> bool:
        """Wait until the graph stops changing (once per process) or `until()`; whether anything other
        than this process was seen."""
        if self._long_lived:
            return True
        if self.spin_time is not None:
            return self._spin(self.spin_time, require_peers, until)
        started = time.monotonic()
        last = self._snapshot()
        baseline = {name for name, _types in last[1]}  # this node's own topics (/parameter_events)
        changed = started
        floor = self._settle_floor()
        while True:
            now = time.monotonic()
            found = bool(last[0]) or bool({name for name, _types in last[1]} - baseline)
            if until is not None and until():
                return True
            # endpoints may come before their node's name (rmw learns names from ros_discovery_info), and a
            # hidden node alone (a graph daemon's, ros2cli's) is often found before the others
            named = any(not hidden_name(self.full_name(n, ns)) for n, ns in last[0])
            quiet = named and now - changed >= GRAPH_QUIET_SECONDS and now - started >= floor
            if found and (self._settled or quiet or now - started >= SETTLE_MAX_SECONDS):
                self._settled = True
                return True
            if not found and now - started >= SETTLE_MAX_SECONDS:
                if require_peers and self.require_peers:
                    raise RostoolError(
                        f"no ROS 2 nodes found on domain {domain_id()} within {SETTLE_MAX_SECONDS:g} s "
                        f"(rclpy backend): is anything running with this ROS_DOMAIN_ID? {self._range_hint()}"
                    )
                return False
            time.sleep(0.05)
            current = self._snapshot()
            if current != last:
                last, changed = current, time.monotonic()

    def _settle_floor(self) -> float:
        from rclpy.utilities import get_rmw_implementation_identifier

        fast = get_rmw_implementation_identifier().startswith("rmw_fastrtps")
        return FASTDDS_SETTLE_MIN_SECONDS if fast else SETTLE_MIN_SECONDS

    def _spin(self, seconds: float, require_peers: bool, until: Callable[[], bool] | None) -> bool:
        """Wait `seconds` from the first listing, as ros2cli's --spin-time (or until `until()`)."""
        _ = self.node
        if self._spin_deadline is None:
            self._spin_deadline = time.monotonic() + seconds
        while time.monotonic() < self._spin_deadline:
            if until is not None and until():
                return True
            time.sleep(min(0.05, max(0.0, self._spin_deadline - time.monotonic())))
        if self.node_pairs():
            return True
        if require_peers and self.require_peers:
            raise RostoolError(
                f"no ROS 2 nodes found on domain {domain_id()} within {seconds:g} s (rclpy backend, "
                f"--spin-time): is anything running with this ROS_DOMAIN_ID? {self._range_hint()}"
            )
        return False

    def _listing(self, nodes: bool = False) -> None:
        self.settle(require_peers=True)

    def wait_for_discovery(self) -> None:
        """Let discovery settle once: a long-lived graph (the daemon's) then answers at once."""
        self.settle()
        self._long_lived = True

    def wait_for_newcomers(self, limit: float = 1.0, ignore: bytes | None = None) -> None:
        """rmw folds in what discovery brings on its own threads: nothing to wait for; a long-lived graph
        notes which nodes have shown endpoints (the daemon calls this every moment), so that one which
        comes and goes between two queries is known for gone when rmw keeps its name."""
        if not self._long_lived:
            return
        listed = set()
        for name, namespace in self.node.get_node_names_and_namespaces():
            full = self.full_name(name, namespace)
            listed.add(full)
            if full not in self._described:
                with contextlib.suppress(RostoolError):
                    if any(self._node_endpoints(full)):
                        self._described.add(full)
        self._described &= listed

    @staticmethod
    def _range_hint() -> str:
        from rostool.graph.rclpy.facts import rclpy_range

        scope, why = rclpy_range()
        return f"Discovery range: {scope} ({why}); `rostool doctor` shows the whole set-up"

    def full_name(self, name: str, namespace: str) -> str:
        if name == UNKNOWN_NODE or namespace.startswith("_NODE_NAMESPACE_UNKNOWN_"):
            return UNKNOWN_NODE
        return f"{namespace.rstrip('/')}/{name}"

    def _endpoints(self, topic: str) -> tuple[list[Any], list[Any]]:
        """(publishers, subscriptions) of `topic` other than this process's, as rmw describes them."""
        node, own = self.node, self._node_name
        pubs = [i for i in node.get_publishers_info_by_topic(topic) if i.node_name != own]
        subs = [i for i in node.get_subscriptions_info_by_topic(topic) if i.node_name != own]
        return pubs, subs

    def _view(self, info: Any, is_writer: bool) -> EndpointView:
        from rostool.graph.rclpy.qos import from_rclpy

        return EndpointView(
            self.full_name(info.node_name, info.node_namespace), is_writer, info.topic_type, type_hash(info),
            bytes(info.endpoint_gid).hex("."), from_rclpy(info.qos_profile),
        )  # fmt: skip

    def topic_views(self, topic: str) -> list[EndpointView]:
        pubs, subs = self._endpoints(topic)
        return [self._view(i, True) for i in pubs] + [self._view(i, False) for i in subs]

    def _all_topic_views(self) -> Iterable[tuple[str, EndpointView]]:
        for name, _types in sorted(self.node.get_topic_names_and_types()):
            for view in self.topic_views(name):
                yield name, view

    def _await_topic(self, topic: str) -> None:
        def published() -> bool:
            return bool(self._endpoints(topic)[0])

        deadline = time.monotonic() + TOPIC_WAIT_SECONDS
        self.settle(until=published)
        while not published() and time.monotonic() < deadline:
            time.sleep(0.05)

    def published_topics(self) -> set[str]:
        if not self._record_settled:  # once: later polls (-a, topics that appear later) must not wait
            self.settle()
            self._record_settled = True
        names = [name for name, _types in self.node.get_topic_names_and_types()]
        return {name for name in names if self._endpoints(name)[0]}

    # --- nodes --------------------------------------------------------------------------------
    def node_names(self) -> list[str]:
        self.settle(require_peers=True)
        return sorted(self.full_name(n, ns) for n, ns in self.node_pairs())  # a name twice: two nodes

    def node_uri(self, name: str) -> str:
        resolved = resolve(name)
        if resolved not in self.node_names():
            raise RostoolError(f"unknown node {resolved}: no ROS 2 participant announces it")
        return f"rclpy:{resolved}"

    def _node_endpoints(self, node: str) -> NodeEndpoints:
        namespace, _, base = node.rpartition("/")
        rcl, ns = self.node, namespace or "/"
        try:
            pubs = rcl.get_publisher_names_and_types_by_node(base, ns)
            subs = rcl.get_subscriber_names_and_types_by_node(base, ns)
            servers = rcl.get_service_names_and_types_by_node(base, ns)
            clients = rcl.get_client_names_and_types_by_node(base, ns)
        except Exception as err:  # NodeNameNonExistentError: gone in the meantime
            raise RostoolError(f"unknown node {node}: {' '.join(str(err).split())}") from None

        def pairs(found: list[tuple[str, list[str]]]) -> set[tuple[str, str]]:
            return {(n, t) for n, types in found for t in types}

        return pairs(pubs), pairs(subs), pairs(servers), pairs(clients)

    def before_node_check(self) -> None:
        self.settle()

    def serves_under(self, prefix: str) -> bool:
        return any(name.startswith(prefix) for name, _types in self.node.get_service_names_and_types())

    def announces_node(self, node: str) -> bool:
        return node in {self.full_name(n, ns) for n, ns in self.node_pairs()}

    # --- topics -------------------------------------------------------------------------------
    def _subscription(
        self, topic: str, on_message: OnMessage, on_error: OnError,
        request: QosRequest | None = None, warn: Callable[[str], None] | None = None,
        type_name: str | None = None,
    ) -> Subscription:  # fmt: skip
        from rostool.graph.rclpy.subscription import RclpySubscription

        return RclpySubscription(self, topic, on_message, on_error, request, warn, type_name)

    def _writer(self, topic: str, store_name: str, profile: QosProfile) -> Writer:
        from rostool.graph.rclpy.qos import to_rclpy

        cls = rtypes.python_class(store_name)
        writer = RclpyWriter(self.node.create_publisher(cls, topic, to_rclpy(profile)))
        self._writers.append(writer)
        return writer

    def store_name(self, type_name: str) -> str:
        """`pkg/Type` or `pkg/msg/Type` -> `pkg/msg/Type`, known to rosbags' store (from the class rclpy
        imports when neither the store nor a source file has it)."""
        from rostool.interfaces.names import to_store_name

        store_name = to_store_name(type_name.strip())
        if not self.types.knows(store_name):
            rtypes.ensure_known(self.types, store_name)
        return store_name

    # --- services and actions -----------------------------------------------------------------
    def service_endpoints(self, nodes: bool = False) -> list[tuple[str, str, list[str], list[str]]]:
        from rostool.graph.rclpy.services import service_endpoints

        return service_endpoints(self)

    def _service_endpoint_views(self, service: str) -> Iterable[ServiceEndpoint]:
        from rostool.graph.rclpy.services import service_endpoint_views

        return service_endpoint_views(self, service)

    def service_client(self, service: str, srv_type: str) -> RclpyServiceClient:
        from rostool.graph.rclpy.services import RclpyServiceClient

        return RclpyServiceClient(self, service, srv_type)

    def _service_server(
        self, service: str, srv_type: str, answer: Callable[[Any], Any]
    ) -> RclpyServiceServer:
        from rostool.graph.rclpy.services import RclpyServiceServer

        return RclpyServiceServer(self, service, srv_type, answer)

    def send_goal(
        self, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> GoalOutcome:
        from rostool.graph.rclpy.actions import GoalRun

        return GoalRun(self, name, kind, goal, timeout, watcher).run()


class RclpyWriter:
    """An rclpy publisher of serialized messages: CDR bytes with their encapsulation header."""

    def __init__(self, writer: Any) -> None:
        self._writer = writer

    def write(self, payload: bytes) -> None:
        self._writer.publish(bytes(payload))

    def matched(self) -> int:
        return int(self._writer.get_subscription_count())

    def wait_acked(self, seconds: float) -> None:
        """Until every reliable subscription acknowledged what was written, at most `seconds`."""
        from rclpy.duration import Duration

        with contextlib.suppress(Exception):  # a publisher rmw already tore down: nothing to wait for
            self._writer.wait_for_all_acked(Duration(nanoseconds=int(seconds * 1e9)))


# A closing process's writers linger until their reliable subscriptions acknowledged what they sent (at
# most this long in all), as Cyclone's do (its WriterLingerDuration, 1 s), which rmw does not do for us: the
# last messages of a `bag play` or `topic pub`, still to be resent to a subscription that matched this
# writer late, were otherwise lost with the writer.
LINGER_SECONDS = 1.0


def _lingered(writers: list[RclpyWriter], seconds: float) -> None:
    deadline = time.monotonic() + seconds
    for writer in writers:
        left = deadline - time.monotonic()
        if left <= 0:
            return
        writer.wait_acked(left)
