"""The ROS 1 Master API and Parameter Server API, with rosmaster's replies.

Every method takes the caller id first and answers [code, message, value]: 1 success, -1 caller error
(bad argument, unknown name), 0 internal failure. Names are resolved against the caller id.
See http://wiki.ros.org/ROS/Master_API and http://wiki.ros.org/ROS/Parameter%20Server%20API.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from typing import Any

from rostool.graph.ros1 import master_names as names
from rostool.graph.ros1.master_names import ANY_TYPE, SEP, ApiError
from rostool.graph.ros1.master_notify import Notifier
from rostool.graph.ros1.master_params import ParamTree, copy_tree, param_updates
from rostool.graph.ros1.master_registry import Kind, Registered, Registry

Reply = tuple[int, str, Any]
Method = Callable[..., Reply]

# API name -> (implementation, value returned on error, number of arguments after caller_id (min, max))
_API: dict[str, tuple[Method, Any, int, int]] = {}


def _api(error_value: Any, nargs: int, max_args: int | None = None) -> Callable[[Method], Method]:
    def register(method: Method) -> Method:
        _API[method.__name__] = (method, error_value, nargs, nargs if max_args is None else max_args)
        return method

    return register


class MasterApi:
    """State and semantics of the master; `_dispatch` is what the XML-RPC server calls."""

    def __init__(self, notifier: Notifier | None = None) -> None:
        self.uri = ""
        self.lock = threading.RLock()
        self.registry = Registry()
        self.params = ParamTree()
        self.notifier = notifier or Notifier()
        self.shutdown_requested = threading.Event()
        self.shutdown_reason = ""

    def _dispatch(self, method: str, params: tuple[Any, ...]) -> Reply:
        spec = _API.get(method)
        if spec is None:
            # Same fault as Python's and rosmaster's XML-RPC servers.
            raise Exception(f'method "{method}" is not supported')
        implementation, error_value, min_args, max_args = spec
        if not params:
            return -1, "missing required caller_id parameter", error_value
        if not min_args <= len(params) - 1 <= max_args:
            return -1, "Error: bad call arity", error_value
        caller_id = params[0]
        if not isinstance(caller_id, str):
            return -1, "caller_id must be a string", error_value
        try:
            return implementation(self, caller_id, *params[1:])
        except ApiError as err:
            return -1, str(err), error_value
        except Exception as err:
            return 0, f"Internal failure: {err}", error_value

    # ----------------------------------------------------------------- master itself

    @_api(0, 0, 1)
    def shutdown(self, caller_id: str, msg: str = "") -> Reply:
        self.shutdown_reason = f"shutdown request from [{caller_id}]" + (f": {msg}" if msg else "")
        self.shutdown_requested.set()
        return 1, "shutdown", 0

    @_api("", 0)
    def getUri(self, caller_id: str) -> Reply:
        return 1, "", self.uri

    @_api(-1, 0)
    def getPid(self, caller_id: str) -> Reply:
        return 1, "", os.getpid()

    # ----------------------------------------------------------------- parameter server

    @_api(0, 1)
    def deleteParam(self, caller_id: str, key: Any) -> Reply:
        key = names.resolve(names.key_arg(key), caller_id)
        with self.lock:
            try:
                self.params.delete(key)
            except KeyError:
                return -1, f"parameter [{key}] is not set", 0
            self._notify_params(key, {}, setter=None)
        return 1, f"parameter {key} deleted", 0

    @_api(0, 2)
    def setParam(self, caller_id: str, key: Any, value: Any) -> Reply:
        key = names.resolve(names.key_arg(key), caller_id)
        names.value_arg(value)
        with self.lock:
            try:
                self.params.set(key, value)
            except TypeError as err:
                raise ApiError(f"Error: invalid arguments: {err}") from None
            self._notify_params(key, value, setter=caller_id)
        return 1, f"parameter {key} set", 0

    @_api(0, 1)
    def getParam(self, caller_id: str, key: Any) -> Reply:
        key = names.resolve(names.key_arg(key), caller_id)
        with self.lock:
            try:
                return 1, f"Parameter [{key}]", self.params.get(key)
            except KeyError:
                return -1, f"Parameter [{key}] is not set", 0

    @_api(0, 1)
    def searchParam(self, caller_id: str, key: Any) -> Reply:
        key = names.key_arg(key)
        with self.lock:
            found = self.params.search(caller_id, key)
        if found:
            return 1, f"Found [{found}]", found
        return -1, f"Cannot find parameter [{key}] in an upwards search", ""

    @_api(0, 2)
    def subscribeParam(self, caller_id: str, caller_api: Any, key: Any) -> Reply:
        caller_api, key, sub_key = _param_subscription_args(caller_id, caller_api, key)
        with self.lock:
            try:
                value = self.params.get(sub_key)
            except KeyError:
                value = {}
            self._register(Kind.PARAM_SUBSCRIPTION, sub_key, caller_id, caller_api)
        return 1, f"Subscribed to parameter [{key}]", value

    @_api(0, 2)
    def unsubscribeParam(self, caller_id: str, caller_api: Any, key: Any) -> Reply:
        caller_api, key, sub_key = _param_subscription_args(caller_id, caller_api, key)
        with self.lock:
            self.registry.unregister(Kind.PARAM_SUBSCRIPTION, sub_key, caller_id, caller_api)
        # rosmaster answers 1 whether or not the caller was subscribed.
        return 1, f"Unsubscribe to parameter [{key}]", 1

    @_api(False, 1)
    def hasParam(self, caller_id: str, key: Any) -> Reply:
        key = names.resolve(names.key_arg(key), caller_id)
        with self.lock:
            return 1, key, self.params.has(key)

    @_api([], 0)
    def getParamNames(self, caller_id: str) -> Reply:
        with self.lock:
            return 1, "Parameter names", self.params.names()

    # ----------------------------------------------------------------- services

    @_api(0, 3)
    def registerService(self, caller_id: str, service: Any, service_api: Any, caller_api: Any) -> Reply:
        service = names.topic_arg(service, caller_id, "service")
        service_api = names.api_arg(service_api, "service_api")
        caller_api = names.api_arg(caller_api, "caller_api")
        with self.lock:
            self._register(Kind.SERVICE, service, caller_id, caller_api, service_api)
        return 1, f"Registered [{caller_id}] as provider of [{service}]", 1

    @_api("", 1)
    def lookupService(self, caller_id: str, service: Any) -> Reply:
        service = names.topic_arg(service, caller_id, "service")
        with self.lock:
            owner = (self.registry.services.service_apis or {}).get(service)
        if owner:
            return 1, f"rosrpc URI: [{owner[1]}]", owner[1]
        return -1, "no provider", ""

    @_api(0, 2)
    def unregisterService(self, caller_id: str, service: Any, service_api: Any) -> Reply:
        service = names.topic_arg(service, caller_id, "service")
        service_api = names.api_arg(service_api, "service_api")
        with self.lock:
            return self.registry.unregister(Kind.SERVICE, service, caller_id, None, service_api)

    # ----------------------------------------------------------------- topics

    @_api([], 3)
    def registerSubscriber(self, caller_id: str, topic: Any, topic_type: Any, caller_api: Any) -> Reply:
        topic, topic_type, caller_api = _endpoint_args(caller_id, topic, caller_api, topic_type)
        with self.lock:
            self._register(Kind.SUBSCRIPTION, topic, caller_id, caller_api)
            # A subscriber may give the type of a topic nobody declared yet, but never '*'.
            if topic not in self.registry.topic_types and topic_type != ANY_TYPE:
                self.registry.topic_types[topic] = topic_type
            publishers = self.registry.publishers.apis(topic)
        return 1, f"Subscribed to [{topic}]", publishers

    @_api(0, 2)
    def unregisterSubscriber(self, caller_id: str, topic: Any, caller_api: Any) -> Reply:
        return self._unregister_endpoint(Kind.SUBSCRIPTION, caller_id, topic, caller_api)

    @_api([], 3)
    def registerPublisher(self, caller_id: str, topic: Any, topic_type: Any, caller_api: Any) -> Reply:
        topic, topic_type, caller_api = _endpoint_args(caller_id, topic, caller_api, topic_type)
        with self.lock:
            self._register(Kind.PUBLICATION, topic, caller_id, caller_api)
            if topic_type != ANY_TYPE or topic not in self.registry.topic_types:
                self.registry.topic_types[topic] = topic_type
            self._notify_publishers(topic)
            subscribers = self.registry.subscribers.apis(topic)
        return 1, f"Registered [{caller_id}] as publisher of [{topic}]", subscribers

    @_api(0, 2)
    def unregisterPublisher(self, caller_id: str, topic: Any, caller_api: Any) -> Reply:
        return self._unregister_endpoint(Kind.PUBLICATION, caller_id, topic, caller_api)

    def _unregister_endpoint(self, kind: Kind, caller_id: str, topic: Any, caller_api: Any) -> Reply:
        topic, _type, caller_api = _endpoint_args(caller_id, topic, caller_api)
        with self.lock:
            reply = self.registry.unregister(kind, topic, caller_id, caller_api)
            if kind == Kind.PUBLICATION and reply[2]:
                self._notify_publishers(topic)  # its subscribers learn that a publisher left
        return reply

    # ----------------------------------------------------------------- graph state

    @_api("", 1)
    def lookupNode(self, caller_id: str, node_name: Any) -> Reply:
        node_name = names.graph_name_arg(node_name, caller_id, "node")
        with self.lock:
            node = self.registry.nodes.get(node_name)
        if node is None:
            return -1, f"unknown node [{node_name}]", ""
        return 1, "node api", node.api

    @_api(0, 1)
    def getPublishedTopics(self, caller_id: str, subgraph: Any) -> Reply:
        subgraph = names.subgraph_arg(subgraph, caller_id)
        if subgraph and not subgraph.endswith(SEP):
            subgraph += SEP
        with self.lock:
            types = self.registry.topic_types
            topics = [[t, types[t]] for t in self.registry.publishers.map if t.startswith(subgraph)]
        return 1, "current topics", topics

    @_api([], 0)
    def getTopicTypes(self, caller_id: str) -> Reply:
        with self.lock:
            return 1, "current system state", [[t, kind] for t, kind in self.registry.topic_types.items()]

    @_api([[], [], []], 0)
    def getSystemState(self, caller_id: str) -> Reply:
        registry = self.registry
        with self.lock:
            state = [r.state() for r in (registry.publishers, registry.subscribers, registry.services)]
        return 1, "current system state", state

    # ----------------------------------------------------------------- callbacks (lock held)

    def _register(
        self, kind: Kind, key: str, caller_id: str, caller_api: str, service_api: str | None = None
    ) -> None:
        result: Registered = self.registry.register(kind, key, caller_id, caller_api, service_api)
        if result.bumped_api is not None:
            reason = f"[{caller_id}] Reason: new node registered with same name"
            self.notifier.post(result.bumped_api, "shutdown", caller_id, reason)
            # rosmaster leaves the old publisher in subscribers' lists; tell them it is gone.
            for topic in result.dropped_publications:
                self._notify_publishers(topic)

    def _notify_publishers(self, topic: str) -> None:
        publishers = self.registry.publishers.apis(topic)
        for api in self.registry.subscribers.apis(topic):
            self.notifier.post(api, "publisherUpdate", topic, topic, publishers)

    def _notify_params(self, key: str, value: Any, setter: str | None) -> None:
        updates = param_updates(self.registry.param_subscribers.map, key, value, setter)
        for subscribers, update_key, update_value in updates:
            snapshot = copy_tree(update_value)
            for _caller_id, api in subscribers:
                self.notifier.post(api, "paramUpdate", update_key, update_key, snapshot)


def _endpoint_args(
    caller_id: str, topic: Any, caller_api: Any, topic_type: Any = ANY_TYPE
) -> tuple[str, str, str]:
    """A topic registration's arguments, checked in rosmaster's order: (topic, type, caller_api); an
    unregistration gives no type."""
    topic = names.topic_arg(topic, caller_id, "topic")
    topic_type = names.type_arg(topic_type)
    return topic, topic_type, names.api_arg(caller_api, "caller_api")


def _param_subscription_args(caller_id: str, caller_api: Any, key: Any) -> tuple[str, str, str]:
    """(caller_api, key, the key subscribers are registered under: a namespace ends in /)."""
    caller_api = names.api_arg(caller_api, "caller_api")
    key = names.resolve(names.key_arg(key), caller_id)
    return caller_api, key, key if key == SEP else names.canonicalize(key) + SEP


def api_methods() -> list[str]:
    """Names of the XML-RPC methods the master answers."""
    return sorted(_API)
