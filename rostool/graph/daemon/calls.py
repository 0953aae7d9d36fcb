"""The verb's side of service calls the graph daemon makes for it (call_server.py): `DaemonCallHost` is what
the shared parameter and call code (ros2_base/params.py, ros2_base/calls.py) asks of a graph, answered by
the daemon, so `param get`, `service call`, lifecycle and logger-level calls take the time of the call
itself and never join the graph (measured: 0.95-1.0 s on the DDS backend and 2.2-4.1 s on the rclpy one
before, with their own participant). Requests are built and replies decoded with this process's types;
the daemon sends rosbags' field definitions of the types it calls with, for those this process lacks.
"""

from __future__ import annotations

import base64
import contextlib
import math
from typing import TYPE_CHECKING, Any, Protocol

from rostool.errors import RostoolError
from rostool.graph.daemon.client import ANSWER_SECONDS, DaemonAbsent, DaemonClient, DaemonSilent, OtherBuild
from rostool.graph.daemon.relay_client import _fielddefs_from_json
from rostool.graph.ros2_base.calls import DEFAULT_REPLY_TIMEOUT
from rostool.graph.ros2_base.names import resolve
from rostool.interfaces.ros2_types import Ros2Types

if TYPE_CHECKING:
    from collections.abc import Sequence


class GraphListings(Protocol):
    """What the call host asks of the graph it serves (a DaemonGraph: its daemon's answers)."""

    def services(self) -> Sequence[tuple[str, str | None, Sequence[str]]]: ...

    def node_names(self) -> list[str]: ...


_GONE = (DaemonAbsent, DaemonSilent, OtherBuild)


class DaemonCallHost:
    """The part of a ROS 2 graph that parameters and service calls use, through the daemon."""

    def __init__(
        self, graph: GraphListings, client: DaemonClient, distro: str, types: Ros2Types | None = None
    ) -> None:
        self._graph = graph
        self._client = client
        self.types: Ros2Types = types if types is not None else CallTypes(distro)

    def resolve(self, name: str) -> str:
        return resolve(name)

    def find_service_type(self, service: str) -> str | None:
        resolved = resolve(service)
        return next((type_ for name, type_, _nodes in self._graph.services() if name == resolved), None)

    def service_client(self, service: str, srv_type: str) -> DaemonServiceClient:
        return DaemonServiceClient(self._client, self.types, resolve(service), srv_type)

    def build_message(self, type_name: str, value: Any) -> Any:
        from rostool.interfaces.fill import build_message

        store_name = self.types.store_name(type_name)
        return build_message(self.types.store, store_name, self.types.with_defaults(store_name, value))

    def message_class(self, type_name: str) -> type:
        return self.types.store.types[self.types.store_name(type_name)]  # type: ignore[no-any-return]

    def before_node_check(self) -> None:
        """The daemon's graph is settled: a node's services are there or not."""

    def serves_under(self, prefix: str) -> bool:
        return any(name.startswith(prefix) for name, _type, _nodes in self._graph.services())

    def announces_node(self, node: str) -> bool:
        return node in self._graph.node_names()


class CallTypes(Ros2Types):
    """Types that start empty: the daemon sends the definitions of every type a call uses (nested ones
    too), so this process does not build its distro's whole store (0.2-0.45 s of a call's 0.3-0.6 s);
    interface source files are still looked in for what the daemon could not describe."""

    @staticmethod
    def _new_store(distro: str) -> Any:
        from rosbags.typesys import Stores, get_typestore

        return get_typestore(Stores.EMPTY)


class DaemonServiceClient:
    """One service's client in the daemon's graph; calls one at a time, as a transport's own client."""

    def __init__(self, client: DaemonClient, types: Ros2Types, service: str, srv_type: str) -> None:
        self._client = client
        self._types = types
        self.service = service
        self._srv_type = srv_type
        described = self._ask({"op": "call_open"}, ANSWER_SECONDS)
        self.request_type = str(described["request"])
        self._response_type = str(described["response"])
        self._learn(described.get("fielddefs") or {})

    def _learn(self, fielddefs: dict[str, Any]) -> None:
        """The request and response types and what they nest: this process's own first (built in, or from
        its interface sources, as a direct client finds them: a .srv's `byte` stays a byte, where a daemon
        that learned the type from the server's description has `uint8`), then the daemon's definitions
        of what is still missing (a type only the daemon's graph or distro knew)."""
        from rostool.interfaces.ros2_srv import register_service

        with contextlib.suppress(RostoolError):  # not known here: the daemon's definitions are
            register_service(self._types, self._srv_type)
        with contextlib.suppress(Exception):  # not readable: the line below says what is missing
            found = _fielddefs_from_json(fielddefs)
            missing = {n: defs for n, defs in found.items() if not self._types.in_store(n)}
            for name in list(missing):
                with contextlib.suppress(Exception):  # a broken source file: the daemon's definition
                    if self._types.knows(name):  # from this process's sources
                        del missing[name]
            self._types.register({n: defs for n, defs in missing.items() if not self._types.in_store(n)})
        if not self._types.in_store(self.request_type):
            raise RostoolError(f"cannot build a request of {self._srv_type}: its definition is unknown here")

    def wait_for_server(self, timeout: float) -> bool:
        wait = min(timeout, DEFAULT_REPLY_TIMEOUT)
        return bool(self._ask({"op": "call_wait", "timeout": wait}, wait + ANSWER_SECONDS))

    def call(self, request: object, timeout: float = 5.0, forever: bool = False) -> Any:
        store = self._types.store
        payload = base64.b64encode(bytes(store.serialize_cdr(request, self.request_type))).decode()
        # the daemon's own timeout ends the call first: this process never gives up on a call the daemon
        # may still make (asked again directly, it would be made twice)
        limit = timeout if not math.isinf(timeout) else (math.inf if forever else DEFAULT_REPLY_TIMEOUT)
        wait = None if math.isinf(limit) else limit + ANSWER_SECONDS
        message = {"op": "call", "request": payload, "timeout": timeout, "forever": forever}
        reply = self._ask(message, wait, made=True)
        return store.deserialize_cdr(base64.b64decode(str(reply)), self._response_type)

    def close(self) -> None:
        """The daemon keeps its client a moment for the next call (call_server.py)."""

    def _ask(self, message: dict[str, Any], timeout: float | None, made: bool = False) -> Any:
        asked = {**message, "build": self._client.build, "service": self.service, "type": self._srv_type}
        try:
            return self._client.request(asked, timeout)
        except _GONE as err:
            maybe = " (it may have been made)" if made else ""
            raise RostoolError(
                f"the graph daemon did not finish the call of {self.service}{maybe}: {err}; call again, "
                "or with --no-daemon"
            ) from None
