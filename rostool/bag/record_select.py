"""Which discovered topics `ros2 bag record` takes: rosbag2_transport's topic filter rules, as a predicate
for the recorder (`RecordOptions.wanted`)."""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.graph.base import Graph

HIDDEN = re.compile(r"(^|/)_")  # ROS 2 hidden names: a token starting with an underscore
SERVICE_EVENT = "/_service_event"


def event_topic(service: str) -> str:
    """The topic a service's introspection events go to."""
    name = service if service.startswith("/") else "/" + service
    return name if name.endswith(SERVICE_EVENT) else name + SERVICE_EVENT


def compile_pattern(pattern: str, flag: str) -> re.Pattern[str] | None:
    if not pattern:
        return None
    try:
        return re.compile(pattern)
    except re.error as err:
        raise RostoolError(f"{flag} {pattern!r}: bad regular expression: {err}") from err


@dataclass(frozen=True)
class TopicRules:
    topics: frozenset[str]
    services: frozenset[str]  # their event topics
    topic_types: frozenset[str]
    all_topics: bool
    all_services: bool
    regex: re.Pattern[str] | None
    exclude_regex: re.Pattern[str] | None
    exclude_topics: frozenset[str]
    exclude_types: frozenset[str]
    exclude_services: frozenset[str]  # their event topics
    hidden: bool
    ignore_leaf: bool = False  # --ignore-leaf-topics: not while no one subscribes (asked again later)


def services_events(names: Iterable[str]) -> frozenset[str]:
    return frozenset(event_topic(name) for name in names)


class TopicSelector:
    """The rules applied to each topic once its type is known (types are asked of `graph`)."""

    def __init__(self, rules: TopicRules) -> None:
        self.rules = rules
        self.graph: Graph | None = None
        self._decided: dict[str, bool] = {}
        self._frozen: set[str] | None = None

    def freeze(self, present: list[str]) -> None:
        """--no-discovery: only what is there now."""
        self._frozen = set(present)

    def __call__(self, topic: str) -> bool:
        known = self._decided.get(topic)
        if known is not None:
            return known
        if self._frozen is not None and topic not in self._frozen:
            return False
        decision = self._decide(topic)
        if decision is not None:
            self._decided[topic] = decision
        return bool(decision)

    def _type(self, topic: str) -> str | None:
        try:
            return self.graph.topic_type(topic) if self.graph is not None else None
        except RostoolError:
            return None

    def _decide(self, topic: str) -> bool | None:
        """True/False, or None while the type it depends on is not known yet."""
        r = self.rules
        is_service = topic.endswith(SERVICE_EVENT)
        if r.exclude_regex is not None and r.exclude_regex.search(topic):
            return False
        if is_service:
            if topic in r.exclude_services:
                return False
            wanted = r.all_services or topic in r.services
            return wanted or bool(r.regex is not None and r.regex.search(topic))
        if topic in r.exclude_topics:
            return False
        if HIDDEN.search(topic) and not r.hidden and topic not in r.topics:
            return False
        needs_type = bool(r.topic_types or r.exclude_types)
        type_name = self._type(topic) if needs_type else None
        if needs_type and type_name is None:
            return None
        if type_name in r.exclude_types:
            return False
        if r.all_topics or topic in r.topics or type_name in r.topic_types:
            return None if r.ignore_leaf and self._leaf(topic) else True
        if r.regex is not None and r.regex.search(topic):
            return None if r.ignore_leaf and self._leaf(topic) else True
        return False

    def _leaf(self, topic: str) -> bool:
        """No subscription in the graph (rosbag2's leaf topic)."""
        try:
            rows = self.graph.topic_endpoints(topic) if self.graph is not None else []
        except RostoolError:
            return True
        return not any(row["endpoint_type"] == "SUBSCRIPTION" for row in rows)
