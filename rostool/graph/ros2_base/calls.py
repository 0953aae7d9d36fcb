"""ROS 2 `service call` and `service info`, built only on what a transport provides (`resolve`,
`find_service_type`, `service_client`, `build_message`, `message_class`; the service's DDS endpoints): one
algorithm and one set of lines for the DDS and the rclpy backends. `ReplyWait` is the call of one
service client both transports share: find the server, then exchange one request for its reply."""

from __future__ import annotations

import math
import re
import threading
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.ros2_base.transport import ServiceEndpoint

if TYPE_CHECKING:
    from rostool.graph.base import ServiceInfo
    from rostool.graph.ros2_base.transport import Ros2Host

SRV_TYPE = re.compile(r"[A-Za-z]\w*/(srv/)?[A-Za-z]\w*\Z")
CALL_WAIT_SECONDS = 5.0  # how long `call` gives a seen (or given) service's server to match without --wait
DEFAULT_REPLY_TIMEOUT = 30.0  # a call given no timeout (inf) still ends after this long without a reply


class ServiceTimeout(RostoolError):
    """No reply within the call's timeout."""


class ReplyWait:
    """The call of one service client: `wait_for_server` (the transport's) first, then `_exchange` (the
    transport's) one request for its reply, one call at a time."""

    service: str

    def __init__(self) -> None:
        self._lock = threading.Lock()

    def wait_for_server(self, timeout: float) -> bool:
        raise NotImplementedError

    def _exchange(self, request: object, deadline: float, timeout: float) -> Any:
        raise NotImplementedError

    def call(self, request: object, timeout: float = 5.0, forever: bool = False) -> Any:
        """The server's reply to `request`. `timeout` covers finding the server and the reply; an infinite
        one is `DEFAULT_REPLY_TIMEOUT` unless `forever` (then the call ends only when the reply comes or
        the server goes away)."""
        if math.isinf(timeout) and not forever:
            timeout = DEFAULT_REPLY_TIMEOUT
        started = time.monotonic()
        if not self.wait_for_server(min(timeout, DEFAULT_REPLY_TIMEOUT)):
            raise RostoolError(
                f"service {self.service} is not available: no server matched within "
                f"{min(timeout, DEFAULT_REPLY_TIMEOUT):g} s (see `rostool service list`; --wait waits longer)"
            )
        with self._lock:
            return self._exchange(request, started + timeout, timeout)

    def _gone(self) -> RostoolError:
        return RostoolError(
            f"the server of {self.service} went away before it replied (see `rostool service list`); "
            "call again when it is back"
        )


def call_service(
    graph: Ros2Host, name: str, values: tuple[str, ...], wait: bool = False, timeout: float | None = None
) -> tuple[Any, Any]:
    """ros2 service call: find the type (an optional TYPE before the values, or the one announced), build
    the request, wait for the server, call. Returns (request, response)."""
    resolved = graph.resolve(name)
    srv_type = values[0] if values and SRV_TYPE.match(values[0]) else None
    if srv_type is not None:
        values = values[1:]
    limit = timeout if timeout is not None else (math.inf if wait else CALL_WAIT_SECONDS)
    deadline = time.monotonic() + limit
    while srv_type is None:
        srv_type = graph.find_service_type(resolved)
        if srv_type is None and (not wait or time.monotonic() >= deadline):
            raise RostoolError(
                f"unknown service {resolved}: no server announces it (see `rostool service list`); "
                "give its TYPE after the name to wait for it with --wait"
            )
        if srv_type is None:
            time.sleep(0.1)
    client = graph.service_client(resolved, srv_type)
    request = graph.build_message(client.request_type, request_value(graph, client.request_type, values))
    remaining = max(deadline - time.monotonic(), 0.001)
    if not client.wait_for_server(remaining):
        announced, asked = graph.find_service_type(resolved), client.request_type.removesuffix("_Request")
        if announced is not None and announced != asked:
            raise RostoolError(f"service {resolved} has type {announced}, not {asked}: call it with that")
        hint = "" if wait else " (--wait waits for it)"
        raise RostoolError(f"service {resolved} is not available: no server matched within {limit:g} s{hint}")
    return request, client.call(request, timeout if timeout is not None else math.inf)


def request_value(graph: Ros2Host, request_type: str, values: tuple[str, ...]) -> Any:
    """One YAML mapping, or the request fields in order (as `rosservice call` takes them)."""
    from rostool.interfaces.values import call_args
    from rostool.output.plain import field_names

    parsed = call_args(values)
    if not parsed:
        return {}
    if len(parsed) == 1 and isinstance(parsed[0], dict):
        return parsed[0]
    fields = field_names(graph.message_class(request_type))
    if len(parsed) != len(fields):
        srv = request_type.removesuffix("_Request")
        raise RostoolError(
            f"{srv} takes {len(fields)} request value(s) in this order: {' '.join(fields) or '(none)'}; "
            f"got {len(parsed)}. Give them in order or as one YAML mapping"
        )
    return dict(zip(fields, parsed, strict=True))


def service_info_facts(resolved: str, endpoints: Iterable[ServiceEndpoint]) -> ServiceInfo | None:
    """ros2 service info's facts: the service's types, its clients and its servers (each with node, type
    hash, and the GIDs and QoS of its request and reply endpoints); None when nobody announces it."""
    # a client writes requests and reads replies, a server the other way round
    sides: dict[tuple[str, str, str], list[ServiceEndpoint]] = {}
    types: set[str] = set()
    for endpoint in endpoints:
        is_client = endpoint.is_writer == (endpoint.kind == "request")
        sides.setdefault(("CLIENT" if is_client else "SERVER", endpoint.node, endpoint.kind), []).append(
            endpoint
        )
        if endpoint.kind == "request":
            types.add(endpoint.service_type)
    if not sides:
        return None
    found: ServiceInfo = {"name": resolved, "types": sorted(types), "clients": [], "servers": []}
    for role, node in sorted({(role, node) for role, node, _ in sides}):
        requests = sides.get((role, node, "request"), [])
        replies = sides.get((role, node, "reply"), [])
        for index in range(max(len(requests), len(replies))):
            pair = {
                "request": requests[index] if index < len(requests) else None,
                "reply": replies[index] if index < len(replies) else None,
            }
            first = pair["request"] or pair["reply"]
            assert first is not None
            found["clients" if role == "CLIENT" else "servers"].append({
                "node": node, "endpoint_type": role, "type": first.service_type, "type_hash": first.type_hash,
                "endpoints": {
                    kind: {"gid": e.gid, "is_writer": e.is_writer, "qos": dict(e.qos)}
                    for kind, e in pair.items() if e is not None
                },
            })  # fmt: skip
    return found
