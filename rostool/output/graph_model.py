"""The node/topic graph `rostool graph` and `rostool bag graph` draw, as rqt_graph shows it.

Built from the live graph (rostool.graph.topology) or from a bag's connections. Renderers (graph_text,
graph_draw) take a `RosGraph` and never a backend.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from rostool.interfaces.names import hidden_name

# what rqt_graph's "hide debug" and ros2cli leave out: logging, parameter events, our own probe node
QUIET_TOPICS = frozenset({"/rosout", "/rosout_agg", "/parameter_events"})
QUIET_NODES = frozenset({"/rosout", "_NODE_NAME_UNKNOWN_"})
OWN_NODE = re.compile(r"^/rostool(_\d+)?$")
# every rclpy/roscpp node serves these: noise in a graph of what the nodes do
HOUSEKEEPING_SERVICES = (
    "describe_parameters", "get_parameter_types", "get_parameters", "list_parameters", "set_parameters",
    "set_parameters_atomically", "get_type_description", "get_loggers", "set_logger_level",
)  # fmt: skip


@dataclass
class TopicEdges:
    name: str
    type: str
    publishers: list[str] = field(default_factory=list)
    subscribers: list[str] = field(default_factory=list)
    count: int | None = None  # messages, for a bag's topics


@dataclass
class ServiceEdges:
    name: str
    type: str | None
    servers: list[str] = field(default_factory=list)
    clients: list[str] = field(default_factory=list)


@dataclass
class RosGraph:
    nodes: list[str]
    topics: list[TopicEdges]
    services: list[ServiceEdges] = field(default_factory=list)
    recorded: bool = False  # a bag's graph: topics have no subscribers to show

    def as_json(self) -> dict[str, Any]:
        return {
            "nodes": self.nodes,
            "topics": [{k: v for k, v in vars(t).items() if v is not None} for t in self.topics],
            "services": [vars(s) for s in self.services],
        }


def in_namespace(name: str, ns: str) -> bool:
    ns = "/" + ns.strip("/")
    return ns == "/" or name == ns or name.startswith(ns + "/")


def quiet_node(name: str) -> bool:
    return name in QUIET_NODES or hidden_name(name) or bool(OWN_NODE.match(name))


def quiet_topic(name: str) -> bool:
    return name in QUIET_TOPICS or hidden_name(name)


def quiet_service(name: str) -> bool:
    return hidden_name(name) or name.rsplit("/", 1)[-1] in HOUSEKEEPING_SERVICES


def select(full: RosGraph, show_all: bool = False, ns: str | None = None) -> RosGraph:
    """Drop the quiet names (unless `show_all`); with `ns`, keep the nodes and topics under it and the
    topics those nodes use (so a namespace's nodes still show what they talk to)."""
    nodes = [n for n in full.nodes if show_all or not quiet_node(n)]
    if ns is not None:
        nodes = [n for n in nodes if in_namespace(n, ns)]
    kept = set(nodes)
    topics = []
    for topic in full.topics:
        pubs, subs = _within(kept, topic.publishers, topic.subscribers)
        inside = ns is not None and in_namespace(topic.name, ns)
        if (show_all or not quiet_topic(topic.name)) and (pubs or subs or inside):
            topics.append(TopicEdges(topic.name, topic.type, pubs, subs))
    found_services = []
    for service in full.services:
        servers, clients = _within(kept, service.servers, service.clients)
        if (show_all or not quiet_service(service.name)) and (servers or clients):
            found_services.append(ServiceEdges(service.name, service.type, servers, clients))
    return RosGraph(nodes, topics, found_services)


def _within(kept: set[str], *ends: list[str]) -> list[list[str]]:
    """Each end's nodes (publishers, subscribers...) that are among `kept`, in their order."""
    return [[n for n in names if n in kept] for names in ends]


def from_bag(reader: Any) -> RosGraph:
    """A bag's topics and types; a ROS 1 bag also names each connection's publishing node (callerid)."""
    topics: dict[str, TopicEdges] = {}
    nodes: set[str] = set()
    for conn in reader.connections:
        msgtype = reader.topics[conn.topic].msgtype
        if reader.ros_version == 1:
            msgtype = msgtype.replace("/msg/", "/")  # rosbag's own form
        entry = topics.setdefault(
            conn.topic, TopicEdges(conn.topic, msgtype, count=reader.topics[conn.topic].count)
        )
        callerid = getattr(conn.ext, "callerid", None)
        if callerid and callerid not in entry.publishers:
            entry.publishers.append(callerid)
            nodes.add(callerid)
    for entry in topics.values():
        entry.publishers.sort()
    return RosGraph(sorted(nodes), [topics[name] for name in sorted(topics)], recorded=True)
