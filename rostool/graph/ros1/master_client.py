"""Client of the ROS 1 Master and Parameter Server XML-RPC APIs."""

from __future__ import annotations

import http.client
import socket
import threading
import xmlrpc.client
from typing import Any
from xml.parsers.expat import ExpatError

from rostool.errors import RostoolError

DEFAULT_TIMEOUT = 5.0
# A host that swallows packets without a word (a VPN that is down, a firewall that drops) would hold every
# call for its whole timeout before the connection even exists; a master or node on any real network
# accepts within a fraction of this. Reads keep the call's own timeout (a busy master may answer slowly).
CONNECT_TIMEOUT = 3.0


class _Connection(http.client.HTTPConnection):
    """An HTTP connection whose connect gives up after CONNECT_TIMEOUT, its reads after its timeout."""

    def connect(self) -> None:
        connect_timeout = CONNECT_TIMEOUT if self.timeout is None else min(CONNECT_TIMEOUT, self.timeout)
        self.sock = socket.create_connection((self.host, self.port), connect_timeout, self.source_address)
        self.sock.settimeout(self.timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host: Any) -> http.client.HTTPConnection:
        # as xmlrpc.client.Transport does (one kept connection per host), with a connect that gives up sooner
        if self._connection and host == self._connection[0]:
            return self._connection[1]
        chost, self._extra_headers, _x509 = self.get_host_info(host)
        self._connection = host, _Connection(chost, timeout=self._timeout)
        return self._connection[1]


def server_proxy(uri: str, timeout: float = DEFAULT_TIMEOUT) -> xmlrpc.client.ServerProxy:
    return xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout), allow_none=False)


class RemoteError(RostoolError):
    """The remote side answered with a failure code."""


class Unreachable(RostoolError):
    """Nothing answered at the URI (refused, timed out, unknown host)."""


_proxies = threading.local()


def _cached_proxy(uri: str, timeout: float) -> xmlrpc.client.ServerProxy:
    """One proxy per thread and (uri, timeout): its HTTP/1.1 connection is reused between calls.

    A ServerProxy is not safe to share between threads, hence the thread-local cache. A connection the
    server closed in between is retried once by xmlrpc.client itself.
    """
    cache: dict[tuple[str, float], xmlrpc.client.ServerProxy] | None = getattr(_proxies, "cache", None)
    if cache is None:
        cache = _proxies.cache = {}
    proxy = cache.get((uri, timeout))
    if proxy is None:
        proxy = cache[(uri, timeout)] = server_proxy(uri, timeout)
    return proxy


def call(uri: str, method: str, *args: Any, what: str, timeout: float = DEFAULT_TIMEOUT) -> Any:
    """Call an XML-RPC method that answers [code, status, value]; return value or raise one clear error."""
    proxy = _cached_proxy(uri, timeout)
    try:
        reply = getattr(proxy, method)(*args)
    except OSError as err:
        _proxies.cache.pop((uri, timeout), None)  # never reuse a connection in an unknown state
        raise Unreachable(f"cannot reach {what} at {uri}: {_reason(err)}") from err
    except (xmlrpc.client.Fault, xmlrpc.client.ProtocolError) as err:
        _proxies.cache.pop((uri, timeout), None)
        raise RostoolError(f"{what} at {uri} failed on {method}: {err}") from err
    except (xmlrpc.client.ResponseError, ExpatError) as err:  # not XML-RPC at all
        _proxies.cache.pop((uri, timeout), None)
        raise MalformedReply(f"{what} at {uri} answered {method} with something that is not XML-RPC") from err
    if not (isinstance(reply, list | tuple) and len(reply) == 3 and type(reply[0]) is int):
        shape = "not [code, status, value]"
        raise MalformedReply(f"{what} at {uri} answered {method} with {_show(reply)}, {shape}")
    code, status, value = reply
    if code != 1:
        raise RemoteError(f"{status}")
    return value


class MalformedReply(RostoolError):
    """The peer answered, but not in the shape its API defines."""


def _show(value: Any, limit: int = 80) -> str:
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _strings(value: Any) -> bool:
    return isinstance(value, list | tuple) and all(isinstance(item, str) for item in value)


def _pairs(value: Any, second: Any = str) -> bool:
    """[[str, X], ...]: what getTopicTypes, getPublishedTopics and each part of getSystemState answer."""
    return isinstance(value, list | tuple) and all(
        isinstance(item, list | tuple) and len(item) == 2 and isinstance(item[0], str) and second(item[1])
        for item in value
    )


def _is_str(value: Any) -> bool:
    return isinstance(value, str)


def _system_state(value: Any) -> bool:
    parts = isinstance(value, list | tuple) and len(value) == 3
    return parts and all(_pairs(part, _strings) for part in value)


def _reason(err: BaseException) -> str:
    if isinstance(err, ConnectionRefusedError):
        return "connection refused"
    if isinstance(err, TimeoutError):
        return "timed out"
    return str(err) or type(err).__name__


class MasterClient:
    """The master's API as seen by one caller (node name)."""

    def __init__(self, uri: str, caller_id: str) -> None:
        self.uri = uri
        self.caller_id = caller_id

    def _checked(self, method: str, valid: Any, *args: Any) -> Any:
        """The value of a master call, checked against the shape the Master API gives it."""
        value = self._call(method, *args)
        if not valid(value):
            raise MalformedReply(
                f"the ROS master at {self.uri} answered {method} with a malformed value {_show(value)}; "
                f"is ROS_MASTER_URI a ROS master?"
            )
        return value

    def _call(self, method: str, *args: Any) -> Any:
        try:
            return call(self.uri, method, self.caller_id, *args, what="the ROS master")
        except Unreachable as err:
            raise RostoolError(
                f"cannot reach the ROS master at {self.uri} (ROS_MASTER_URI); start one with "
                "`rostool core` or `roscore`, or point ROS_MASTER_URI at a running master"
            ) from err

    # Master API
    def get_pid(self) -> int:
        return int(self._checked("getPid", lambda v: type(v) is int))

    def system_state(self) -> tuple[list[Any], list[Any], list[Any]]:
        publishers, subscribers, services = self._checked("getSystemState", _system_state)
        return publishers, subscribers, services

    def topic_types(self) -> dict[str, str]:
        return dict(self._checked("getTopicTypes", _pairs))

    def published_topics(self, subgraph: str = "") -> dict[str, str]:
        return dict(self._checked("getPublishedTopics", _pairs, subgraph))

    def lookup_node(self, name: str) -> str:
        return str(self._checked("lookupNode", _is_str, name))

    def lookup_service(self, name: str) -> str:
        return str(self._checked("lookupService", _is_str, name))

    def register_publisher(self, topic: str, type_name: str, api: str) -> list[str]:
        return list(self._checked("registerPublisher", _strings, topic, type_name, api))

    def unregister_publisher(self, topic: str, api: str) -> None:
        self._call("unregisterPublisher", topic, api)

    def register_subscriber(self, topic: str, type_name: str, api: str) -> list[str]:
        return list(self._checked("registerSubscriber", _strings, topic, type_name, api))

    def unregister_subscriber(self, topic: str, api: str) -> None:
        self._call("unregisterSubscriber", topic, api)

    def register_service(self, service: str, service_api: str, api: str) -> None:
        self._call("registerService", service, service_api, api)

    def unregister_service(self, service: str, service_api: str) -> None:
        self._call("unregisterService", service, service_api)

    # Parameter server API
    def get_param(self, key: str) -> Any:
        return self._call("getParam", key)

    def set_param(self, key: str, value: Any) -> None:
        self._call("setParam", key, value)

    def delete_param(self, key: str) -> None:
        self._call("deleteParam", key)

    def has_param(self, key: str) -> bool:
        return bool(self._call("hasParam", key))

    def param_names(self) -> list[str]:
        return list(self._checked("getParamNames", _strings))

    def search_param(self, key: str) -> str:
        return str(self._checked("searchParam", _is_str, key))
