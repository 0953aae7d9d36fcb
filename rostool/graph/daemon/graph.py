"""`DaemonGraph`: the Graph protocol with its read-only queries answered by the user's graph daemon, its
subscriptions relayed by it (echo, hz, bw, plot, and `bag record`'s: record_relay.py), its parameters and
service calls made by it (calls.py: also lifecycle's and logger levels'), its goals sent by it
(goal_client.py), and everything else (pub, serving) by a direct backend made on first need.

When no daemon answers, the query is answered directly (complete, as without a daemon) and a daemon is
started detached for the next calls; a daemon that takes the connection but does not answer in time is
bypassed with one warning line; a daemon of another build is replaced.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from dataclasses import asdict
from typing import TYPE_CHECKING, Any, Literal

from rostool.errors import RostoolError
from rostool.graph.daemon.client import DaemonAbsent, DaemonClient, DaemonSilent, NotRelayed, OtherBuild
from rostool.graph.daemon.place import PlaceRefused
from rostool.graph.daemon.queries import SERVED
from rostool.graph.ros2_base.names import resolve

if TYPE_CHECKING:
    from rostool.graph.base import (
        ActionInfo,
        ActionSummary,
        GoalOutcome,
        GoalWatcher,
        Graph,
        NodeInfo,
        OnError,
        OnMessage,
        Parameters,
        ServiceInfo,
        Subscription,
        TopicEndpoint,
        TopicInfo,
    )
    from rostool.graph.daemon.calls import DaemonCallHost
    from rostool.graph.daemon.lent_types import LentTypes
    from rostool.graph.daemon.relay_client import RelayedSubscription
    from rostool.graph.qos import QosRequest
    from rostool.graph.recording import Encoding, RecordSource


# how long a call waits for a daemon that is starting: it serves once its interpreter is up and its graph
# has settled, 2-3 s after its spawn on the DDS backend, 4-5 s on the rclpy backend (a 3.3 s floor with Fast
# DDS), and a cold call answering directly (1.4 s, 3.5 s) may not have spawned it yet; past this (a daemon
# stuck starting), the call answers directly
STARTING_DAEMON_SECONDS = 10.0


class DaemonGraph:
    ros_version = 2
    style: Literal["ros1", "ros2"] = "ros2"
    encoding: Encoding = "cdr"

    def __init__(
        self, client: DaemonClient, direct: Callable[[], Graph], wait_for_starting: bool = True
    ) -> None:
        self._client = client
        self._make_direct = direct
        # False with --spin-time: the direct wait it sets is what was asked for
        self._wait_for_starting = wait_for_starting
        self._direct: Graph | None = None
        self._direct_lock = threading.Lock()  # a relay's reading thread may need it too
        self._bypass = False
        self._qos: QosRequest | None = None
        self._types: LentTypes | None = None
        self._relays: list[RelayedSubscription] = []

    # --- the direct backend ----------------------------------------------------------------------
    @property
    def direct(self) -> Graph:
        with self._direct_lock:
            if self._direct is None:
                direct = self._make_direct()
                if self._qos is not None:
                    direct.use_qos(self._qos)
                if self._types is not None:
                    self._types.lend_to(direct.types)
                self._direct = direct
            return self._direct

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.direct, name)

    @property
    def types(self) -> Any:
        """The direct graph's types once it exists. Before (a relayed subscription needs no direct graph),
        types of the daemon's distro, whose store the direct graph made later shares (bag play registers a
        bag's types before it publishes; service call makes its field lookup before it calls)."""
        if self._direct is None and self._types is None and not self._bypass:
            distro = self._daemon_distro()
            if distro is not None:
                from rostool.graph.daemon.lent_types import LentTypes  # the store: after discovery starts

                self._types = LentTypes(distro)
        if self._direct is None and self._types is not None:
            return self._types
        return self.direct.types

    def _daemon_distro(self) -> str | None:
        """The distro the daemon decodes with (its key makes it this process's); None when it does not
        answer (as any query: a daemon is started, or bypassed with a warning)."""
        try:
            found = self._served(lambda: str(self._client.query("type_distro", [])), lambda: None)
        except RostoolError:
            return None
        return found if isinstance(found, str) else None

    def use_qos(self, qos: QosRequest) -> None:
        self._qos = qos
        if self._direct is not None:
            self._direct.use_qos(qos)

    def subscribe(self, topic: str, on_message: OnMessage, on_error: OnError | None = None) -> Subscription:
        """A subscription relayed by the daemon, whose reader already matched the topic's publishers (the
        first message comes without this process joining the graph); directly when no daemon serves."""
        return self.relayed_subscription(topic, on_message, on_error or self._warn, self._warn)

    def relayed_subscription(
        self, topic: str, on_message: OnMessage, on_error: OnError, warn: Callable[[str], None]
    ) -> Subscription:
        """`subscribe` with the relay's warnings (a daemon that stopped relaying, messages it dropped) said
        through `warn`."""

        def directly() -> Subscription:
            return self.direct.subscribe(topic, on_message, on_error)

        def relayed() -> Subscription:
            from rostool.graph.daemon.relay_client import RelayedSubscription

            resolved = resolve(topic)
            qos = asdict(self._qos) if self._qos is not None else {}
            try:
                sock = self._client.relay(resolved, qos)
            except PlaceRefused:
                raise
            except (NotRelayed, RostoolError):  # the direct subscription says what is wrong, if anything
                return directly()
            relay = RelayedSubscription(sock, resolved, self.types, on_message, on_error, warn, directly)
            self._relays.append(relay)
            return relay

        return self._served(relayed, directly)  # type: ignore[no-any-return]

    def record_source(self, warn: Callable[[str], None], include_hidden: bool = False) -> RecordSource:
        """`bag record` from the first instant: while the daemon serves, the topics it shows are recorded
        through relays, whose readers join a graph that already knows the publishers (measured: the first
        message 0.1 s after subscribing, instead of a second or more for a participant of this process to be
        discovered); the direct source otherwise (no daemon yet: it is started for the next call)."""
        if self._bypass or self._daemon_distro() is None:
            return self.direct.record_source(warn, include_hidden)  # type: ignore[attr-defined,no-any-return]
        from rostool.graph.daemon.record_relay import RelayedRecordSource

        return RelayedRecordSource(self, warn, include_hidden)

    # --- calls the daemon makes for this process -------------------------------------------------------
    def _call_host(self) -> DaemonCallHost | None:
        """Parameters and service calls through the daemon while it serves (calls.py); None: directly."""
        distro = None if self._bypass else self._daemon_distro()
        if distro is None:
            return None
        from rostool.graph.daemon.calls import DaemonCallHost

        # types the verb made already (a renderer's field lookup holds their store: the call's types must
        # land there), else a store of the call's types only (calls.CallTypes)
        made = self._direct.types if self._direct is not None else self._types
        return DaemonCallHost(self, self._client, distro, made)

    def parameters(self, node: str | None, timeout: float = 5.0) -> Parameters:
        host = self._call_host()
        if host is None or node is None:
            return self.direct.parameters(node, timeout)
        from rostool.graph.ros2_base.params import NodeParameters

        return NodeParameters(host, node, timeout)  # type: ignore[arg-type]

    def service_call(
        self, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
    ) -> tuple[Any, Any]:
        host = self._call_host()
        if host is None:
            return self.direct.service_call(name, values, wait, timeout)
        from rostool.graph.ros2_base.calls import call_service

        return call_service(host, name, values, wait, timeout)  # type: ignore[arg-type]

    def send_goal(
        self, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> GoalOutcome:
        """`action send-goal` sent by the daemon, whose graph knows the server already (goal_client.py); the
        verb's watcher is told what a direct run tells it. Directly when no daemon serves."""

        def directly() -> GoalOutcome:
            return self.direct.send_goal(name, kind, goal, timeout, watcher)

        def through() -> GoalOutcome:
            from rostool.graph.daemon.goal_client import send_goal_through

            return send_goal_through(self._client, name, kind, goal, timeout, watcher, directly)

        return self._served(through, directly)  # type: ignore[no-any-return]

    def close(self) -> None:
        for relay in self._relays:
            relay.close()
        self._relays.clear()
        if self._direct is not None:
            self._direct.close()
            self._direct = None

    def __enter__(self) -> DaemonGraph:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def resolve(self, name: str) -> str:
        return resolve(name)

    def publisher(self, topic: str, type_name: str, latch: bool = False) -> Any:
        """The direct graph's publisher; the topic's type, which it must not contradict, is the daemon's."""
        resolved = resolve(topic)
        try:
            existing = next((info.type for info in self.topics() if info.name == resolved), None)
        except RostoolError:  # nobody else in the graph
            existing = None
        return self.direct.publisher(topic, type_name, latch, existing)  # type: ignore[call-arg]

    # --- queries ---------------------------------------------------------------------------------
    def _ask(self, method: str, *args: Any) -> Any:
        def asked() -> Any:
            own = getattr(self._direct, "participant_guid", None) if self._direct is not None else None
            return SERVED[method][1](self._client.query(method, list(args), own))

        return self._served(asked, lambda: getattr(self.direct, method)(*args))

    def _served(self, ask: Callable[[], Any], directly: Callable[[], Any]) -> Any:
        """`ask()` the daemon; `directly()` when it cannot answer (from then on, for this process). A daemon
        that is missing (or of another build) is started once the direct answer is known: started before,
        its participant, still describing itself, is one more the direct listing waits for (measured: a
        cold `node list` waited until 2.7 s for it, instead of 1.2-1.5 s), and its start-up takes the CPU
        this process needs. Not so when the direct listing waits a floor whatever the graph (`waits_long`,
        the rclpy backend's): then the daemon starts beside it, and is ready seconds sooner. A daemon
        already starting is waited for (`_from_starting_daemon`)."""
        start: Callable[[], Any] | None = None
        if not self._bypass:
            try:
                return ask()
            except DaemonAbsent:
                starting = self._client.lock_holder() is not None or not self._client.claim_cold_call()
                if starting and self._wait_for_starting:
                    served = self._from_starting_daemon(ask)
                    if served:
                        return served[0]
                direct = self.direct  # its discovery starts now, whatever `directly` does first
                start = self._start
                if getattr(direct, "waits_long", False):
                    start()
                    start = None
            except OtherBuild:
                start = self._replace
            except DaemonSilent as err:
                self._warn_silent(err)
            except PlaceRefused as err:
                self._warn(f"{err}; answering directly")
            self._bypass = True
        if start is None:
            return directly()
        try:
            answer = directly()
        except RostoolError:
            start()
            raise
        start()
        return answer

    def _from_starting_daemon(self, ask: Callable[[], Any]) -> tuple[Any] | None:
        """The answer of a daemon that is starting (its lock held: it settles its graph before it serves)
        or that the key's cold call is about to start, or None to answer directly (nobody brings one, or it
        is stuck). That daemon began sooner, so it serves sooner than a direct answer begun now would come
        (measured, a call right after a cold one: 0.6 s instead of 3.5 s on the rclpy backend, 1.1-1.3 s
        instead of 2.7 s on the DDS backend). Asked before this process joins the graph: its participant
        would be one more the starting daemon waits for (a bare DDS one, up to its grace), and an rclpy
        one's node would be in the daemon's answer."""
        deadline = time.monotonic() + STARTING_DAEMON_SECONDS
        while time.monotonic() < deadline:
            time.sleep(0.1)
            try:
                return (ask(),)
            except DaemonAbsent:
                if self._client.lock_holder() is None and not self._client.cold_call_elsewhere():
                    return None  # it ended without serving, or the cold call ended without starting it
            except DaemonSilent as err:
                self._warn_silent(err)
                return None
            except (OtherBuild, PlaceRefused):
                return None
        self._warn(f"the graph daemon did not serve within {STARTING_DAEMON_SECONDS:g} s of this call; "
                   "answering directly (`rostool daemon stop` resets it)")  # fmt: skip
        return None

    def _replace(self) -> None:
        self._client.start_detached(replacing=True, auto=True)  # it waits for the old one's lock

    def _start(self) -> None:
        if self._client.lock_holder() is None:
            self._client.start_detached(auto=True)

    def _warn_silent(self, err: DaemonSilent) -> None:
        self._warn(f"the graph daemon did not answer ({err}); answering directly "
                   "(`rostool daemon stop` resets it)")  # fmt: skip

    @staticmethod
    def _warn(text: str) -> None:
        print(f"WARNING: {text}", file=sys.stderr)

    def node_names(self) -> list[str]:
        return self._ask("node_names")  # type: ignore[no-any-return]

    def node_uri(self, name: str) -> str:
        return self._ask("node_uri", resolve(name))  # type: ignore[no-any-return]

    def node_info(self, name: str) -> NodeInfo:
        return self._ask("node_info", resolve(name))  # type: ignore[no-any-return]

    def topics(self) -> list[TopicInfo]:
        return self._ask("topics")  # type: ignore[no-any-return]

    def topic_type(self, name: str) -> str | None:
        return self._ask("topic_type", resolve(name))  # type: ignore[no-any-return]

    def topic_endpoints(self, name: str) -> list[TopicEndpoint]:
        return self._ask("topic_endpoints", resolve(name))  # type: ignore[no-any-return]

    def services(self) -> list[tuple[str, str | None, list[str]]]:
        return self._ask("services")  # type: ignore[no-any-return]

    def service_type(self, name: str) -> str:
        return self._ask("service_type", resolve(name))  # type: ignore[no-any-return]

    def find_services(self, type_name: str) -> list[str]:
        return self._ask("find_services", type_name)  # type: ignore[no-any-return]

    def service_info(self, name: str) -> ServiceInfo | None:
        return self._ask("service_info", resolve(name))  # type: ignore[no-any-return]

    def actions(self) -> list[ActionSummary]:
        return self._ask("actions")  # type: ignore[no-any-return]

    def action_info(self, name: str, wait: float) -> ActionInfo:
        return self._ask("action_info", resolve(name), wait)  # type: ignore[no-any-return]


def daemon_graph(
    requested_backend: str | None, direct: Callable[[], Graph], wait_for_starting: bool = True
) -> Graph:
    """The graph the verbs get when a daemon may serve: a DaemonGraph, or the direct backend (with one
    warning line) when the user's daemon directory is not private. `wait_for_starting`: a query that finds
    the daemon starting waits for it (False: it answers directly, as `--spin-time` asks)."""
    from rostool.graph.rclpy.select import requested
    from rostool.graph.ros2_base.env import discovery_range

    backend = requested(requested_backend)[0]
    discovery_range()  # a bad value fails in one line here, not in a daemon that never starts
    try:
        client = DaemonClient(backend)
    except PlaceRefused as err:
        DaemonGraph._warn(f"{err}; answering directly")
        return direct()
    return DaemonGraph(client, direct, wait_for_starting)  # type: ignore[return-value]
