"""`DaemonGraph`: the Graph protocol with its read-only queries answered by the user's graph daemon, and
everything else (echo, pub, call, record, goals, parameters, types) by a direct backend made on first need.

When no daemon answers, the query is answered directly (complete, as without a daemon) and a daemon is
started detached for the next calls; a daemon that takes the connection but does not answer in time is
bypassed with one warning line; a daemon of another build is replaced.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

from rostool.errors import RostoolError
from rostool.graph.daemon.client import DaemonAbsent, DaemonClient, DaemonSilent, OtherBuild
from rostool.graph.daemon.place import PlaceRefused
from rostool.graph.daemon.queries import SERVED
from rostool.graph.ros2_base.names import resolve

if TYPE_CHECKING:
    from rostool.graph.base import (
        ActionInfo,
        ActionSummary,
        Graph,
        NodeInfo,
        ServiceInfo,
        TopicEndpoint,
        TopicInfo,
    )
    from rostool.graph.recording import Encoding


class DaemonGraph:
    ros_version = 2
    style: Literal["ros1", "ros2"] = "ros2"
    encoding: Encoding = "cdr"

    def __init__(self, client: DaemonClient, direct: Callable[[], Graph]) -> None:
        self._client = client
        self._make_direct = direct
        self._direct: Graph | None = None
        self._bypass = False

    # --- the direct backend ----------------------------------------------------------------------
    @property
    def direct(self) -> Graph:
        if self._direct is None:
            self._direct = self._make_direct()
        return self._direct

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.direct, name)

    @property
    def types(self) -> Any:
        return self.direct.types

    def close(self) -> None:
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
        if not self._bypass:
            try:
                own = getattr(self._direct, "participant_guid", None) if self._direct is not None else None
                return SERVED[method][1](self._client.query(method, list(args), own))
            except DaemonAbsent:
                # the direct graph's discovery first: the daemon's start-up would otherwise take the CPU
                # this process needs to start its own participant
                direct = self.direct
                self._start()
                self._bypass = True
                return getattr(direct, method)(*args)
            except OtherBuild:
                self._client.start_detached(replacing=True)  # it waits for the old one's lock
            except DaemonSilent as err:
                self._warn(f"the graph daemon did not answer ({err}); answering directly "
                           "(`rostool daemon stop` resets it)")  # fmt: skip
            except PlaceRefused as err:
                self._warn(f"{err}; answering directly")
            self._bypass = True
        return getattr(self.direct, method)(*args)

    def _start(self) -> None:
        if self._client.lock_holder() is None:
            self._client.start_detached()

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


def daemon_graph(requested_backend: str | None, direct: Callable[[], Graph]) -> Graph:
    """The graph the verbs get when a daemon may serve: a DaemonGraph, or the direct backend (with one
    warning line) when the user's daemon directory is not private."""
    from rostool.graph.rclpy.select import requested
    from rostool.graph.ros2_base.env import discovery_range

    backend = requested(requested_backend)[0]
    discovery_range()  # a bad value fails in one line here, not in a daemon that never starts
    try:
        client = DaemonClient(backend)
    except PlaceRefused as err:
        DaemonGraph._warn(f"{err}; answering directly")
        return direct()
    return DaemonGraph(client, direct)  # type: ignore[return-value]
