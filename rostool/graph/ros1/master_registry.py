"""Who publishes, subscribes, provides services and watches parameters, per node.

Mirrors rosmaster's bookkeeping: a node is known while it has at least one registration; when a node
registers again under the same name with another XML-RPC URI, the old registrations are dropped and the
old process must be told to shut down (the caller does that with `Registered.bumped_api`).
Not thread-safe: the master holds its lock around every call.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

Reply = tuple[int, str, int]


class Kind(Enum):
    SUBSCRIPTION = "subscription"
    PUBLICATION = "publication"
    SERVICE = "service"
    PARAM_SUBSCRIPTION = "param_subscription"


@dataclass
class Node:
    caller_id: str
    api: str
    keys: dict[Kind, list[str]] = field(default_factory=lambda: {kind: [] for kind in Kind})

    def is_empty(self) -> bool:
        return not any(self.keys.values())


class Registrations:
    """A multimap key -> [(caller_id, caller_api)]; for services also key -> (caller_id, service_api)."""

    def __init__(self, kind: Kind) -> None:
        self.kind = kind
        self.map: dict[str, list[tuple[str, str]]] = {}
        self.service_apis: dict[str, tuple[str, str]] | None = None

    def apis(self, key: str) -> list[str]:
        return [api for _caller, api in self.map.get(key, [])]

    def state(self) -> list[list[object]]:
        """getSystemState form: [[key, [caller_id, ...]], ...]."""
        return [[key, [caller for caller, _api in providers]] for key, providers in self.map.items()]

    def register(self, key: str, caller_id: str, caller_api: str, service_api: str | None = None) -> None:
        if service_api is not None:
            # One provider per service: the latest registration wins.
            self.map[key] = [(caller_id, caller_api)]
            if self.service_apis is None:
                self.service_apis = {}
            self.service_apis[key] = (caller_id, service_api)
            return
        providers = self.map.setdefault(key, [])
        if (caller_id, caller_api) not in providers:
            providers.append((caller_id, caller_api))

    def unregister(self, key: str, caller_id: str, caller_api: str | None, service_api: str | None) -> Reply:
        if self.kind is Kind.SERVICE:
            if self.service_apis is None:
                return 1, f"[{caller_id}] is not a provider of [{key}]", 0
            if self.service_apis.get(key) != (caller_id, service_api):
                return 1, f"[{service_api}] is no longer the current service api handle for [{key}]", 0
            del self.service_apis[key]
            del self.map[key]
            return 1, f"Unregistered [{caller_id}] as provider of [{key}]", 1
        providers = self.map.get(key, [])
        entry = (caller_id, caller_api or "")
        if entry not in providers:
            return 1, f"[{caller_id}] is not a known provider of [{key}]", 0
        providers.remove(entry)
        if not providers:
            del self.map[key]
        return 1, f"Unregistered [{caller_id}] as provider of [{key}]", 1

    def unregister_all(self, caller_id: str) -> list[str]:
        """Drop every registration of `caller_id`; returns the keys it had."""
        touched: list[str] = []
        for key in list(self.map):
            providers = self.map[key]
            kept = [entry for entry in providers if entry[0] != caller_id]
            if len(kept) != len(providers):
                touched.append(key)
            if kept:
                self.map[key] = kept
            else:
                del self.map[key]
        if self.service_apis:
            for key in [k for k, (owner, _api) in self.service_apis.items() if owner == caller_id]:
                del self.service_apis[key]
        return touched


@dataclass
class Registered:
    """What a registration changed beyond itself."""

    bumped_api: str | None = None  # XML-RPC URI of the replaced node, to be shut down
    dropped_publications: list[str] = field(default_factory=list)  # topics it published


class Registry:
    def __init__(self) -> None:
        self.nodes: dict[str, Node] = {}
        self.by_kind = {kind: Registrations(kind) for kind in Kind}
        self.publishers = self.by_kind[Kind.PUBLICATION]
        self.subscribers = self.by_kind[Kind.SUBSCRIPTION]
        self.services = self.by_kind[Kind.SERVICE]
        self.param_subscribers = self.by_kind[Kind.PARAM_SUBSCRIPTION]
        self.topic_types: dict[str, str] = {}

    def register(
        self, kind: Kind, key: str, caller_id: str, caller_api: str, service_api: str | None = None
    ) -> Registered:
        result = Registered()
        node = self.nodes.get(caller_id)
        if node is None or node.api != caller_api:
            if node is not None:
                result.bumped_api = node.api
                for registrations in self.by_kind.values():
                    dropped = registrations.unregister_all(caller_id)
                    if registrations is self.publishers:
                        result.dropped_publications = dropped
            node = self.nodes[caller_id] = Node(caller_id, caller_api)
        if key not in node.keys[kind]:
            node.keys[kind].append(key)
        self.by_kind[kind].register(key, caller_id, caller_api, service_api)
        return result

    def unregister(
        self, kind: Kind, key: str, caller_id: str, caller_api: str | None, service_api: str | None = None
    ) -> Reply:
        node = self.nodes.get(caller_id)
        if node is None:
            return 1, f"[{caller_id}] is not a registered node", 0
        reply = self.by_kind[kind].unregister(key, caller_id, caller_api, service_api)
        if reply[2] == 1 and key in node.keys[kind]:
            node.keys[kind].remove(key)
        if node.is_empty():
            del self.nodes[caller_id]
        return reply
