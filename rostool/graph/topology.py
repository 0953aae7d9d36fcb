"""The live graph as `rostool graph` draws it: nodes, topics and services read through the `Graph` protocol
(any ROS version or backend), filtered as rqt_graph filters them."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rostool.output.graph_model import RosGraph, ServiceEdges, TopicEdges, quiet_node, select

if TYPE_CHECKING:
    from rostool.graph.base import Graph


def collect(graph: Graph, services: bool = False, show_all: bool = False, ns: str | None = None) -> RosGraph:
    """The live graph: every node, topic and (with `services`) service, filtered like rqt_graph."""
    nodes = set(graph.node_names())
    topics = [TopicEdges(t.name, t.type, sorted(t.publishers), sorted(t.subscribers)) for t in graph.topics()]
    nodes.update(n for t in topics for n in (*t.publishers, *t.subscribers))
    found_services: list[ServiceEdges] = []
    if services:
        found_services = [
            ServiceEdges(name, kind, sorted(servers)) for name, kind, servers in graph.services()
        ]
        if graph.style == "ros2":
            # ROS 2 endpoints say who calls a service; a ROS 1 master only knows servers, and asking
            # every ROS 1 node over XML-RPC would not tell either
            by_name = {s.name: s for s in found_services}
            for node in sorted(nodes):
                if quiet_node(node) and not show_all:
                    continue
                for name, kind in graph.node_info(node).service_clients:
                    entry = by_name.setdefault(name, ServiceEdges(name, kind))
                    entry.clients.append(node)
            found_services = sorted(by_name.values(), key=lambda s: s.name)
    return select(RosGraph(sorted(nodes), topics, found_services), show_all, ns)
