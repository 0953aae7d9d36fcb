"""What `node info` prints: rosnode info's sections (and its JSON), ros2 node info's endpoints by kind."""

from __future__ import annotations

from typing import Any

from rostool.interfaces.names import hidden_name

_SEND_GOAL = "/_action/send_goal"

Entries = list[tuple[str, str]]  # (name, type)


def node_info_json(details: Any) -> dict[str, Any]:
    """A node's details (graph.base.NodeInfo) as `node info --json` prints them on ROS 1."""
    return {
        "name": details.name,
        "uri": details.uri,
        "pid": details.pid,
        "publications": [{"topic": t, "type": ty} for t, ty in details.publications],
        "subscriptions": [{"topic": t, "type": ty} for t, ty in details.subscriptions],
        "services": details.services,
        "connections": [vars(c) for c in details.connections],
    }


def node_info_text(details: Any, uris: dict[str, str]) -> str:
    """rosnode info's text; `uris` (node -> URI) names the peers of the connections."""
    by_uri = {uri: n for n, uri in uris.items()}
    lines = ["-" * 80, f"Node [{details.name}]"]
    for title, entries in (("Publications", details.publications), ("Subscriptions", details.subscriptions)):
        if entries:
            lines += [f"{title}: ", *(f" * {t} [{ty}]" for t, ty in entries), ""]
        else:
            lines += [f"{title}: None", ""]
    if details.services:
        lines += ["Services: ", *(f" * {s}" for s in details.services), ""]
    else:
        lines += ["Services: None", ""]
    lines += ["", f"contacting node {details.uri} ...", f"Pid: {details.pid}"]
    if details.connections:
        lines.append("Connections:")
        for c in details.connections:
            peer = f"{by_uri[c.peer]} ({c.peer})" if c.peer in by_uri else c.peer
            lines += [
                f" * topic: {c.topic}",
                f"    * to: {peer}",
                f"    * direction: {c.direction}",
                f"    * transport: {c.transport}",
            ]
    return "\n".join(lines) + "\n"


def ros2_node_groups(details: Any, include_hidden: bool = False) -> tuple[tuple[str, Entries], ...]:
    """ros2 node info's sections: the node's endpoints grouped by kind, with their types; actions are told
    by their hidden services, which (as every hidden name) show only with --include-hidden."""

    def shown(entries: Entries) -> Entries:
        return sorted(e for e in entries if include_hidden or not hidden_name(e[0]))

    servers = [(s, details.service_types.get(s, "?")) for s in details.services]
    return (
        ("Subscribers", shown(details.subscriptions)), ("Publishers", shown(details.publications)),
        ("Service Servers", shown(servers)), ("Service Clients", shown(details.service_clients)),
        ("Action Servers", _actions(servers)), ("Action Clients", _actions(details.service_clients)),
    )  # fmt: skip


def ros2_node_text(name: str, groups: tuple[tuple[str, Entries], ...]) -> str:
    lines = [name]
    for title, entries in groups:
        lines.append(f"  {title}:")
        # ros2 prints an empty section as its title and an empty line
        lines += [f"    {n}: {t}" for n, t in entries] or [""]
    return "\n".join(lines)


def _actions(services: Entries) -> Entries:
    """Actions told by their send_goal service: (/fibonacci, pkg/action/Fibonacci)."""
    return sorted(
        (n.removesuffix(_SEND_GOAL), t.removesuffix("_SendGoal"))
        for n, t in services
        if n.endswith(_SEND_GOAL)
    )
