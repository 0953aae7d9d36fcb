"""ros2 topic info's and ros2 service info's text: a type, the endpoint counts, with -v every endpoint's block
(node, type, hash, GID, QoS) as rclpy's TopicEndpointInfo and ServiceEndpointInfo print them."""

from __future__ import annotations

from typing import Any

_SERVICE_TITLES = {
    ("CLIENT", "request"): "Request Writer", ("CLIENT", "reply"): "Response Reader",
    ("SERVER", "request"): "Request Reader", ("SERVER", "reply"): "Response Writer",
}  # fmt: skip


def topic_info_text(type_name: str, endpoints: list[dict[str, Any]], verbose: bool) -> str:
    """ros2 topic info: type and counts, with -v every endpoint; each item (the type, a count, an endpoint's
    block) on its line(s), with -v each followed by an empty line. Ends with a newline."""
    items = [f"Type: {type_name}"]
    for title, kind in (("Publisher", "PUBLISHER"), ("Subscription", "SUBSCRIPTION")):
        rows = [e for e in endpoints if e["endpoint_type"] == kind]
        items.append(f"{title} count: {len(rows)}")
        for row in rows if verbose else []:
            qos = row["qos"]
            lines = [
                *_node_lines(row, "Topic", kind), f"GID: {row['gid']}", "QoS profile:", *qos_lines(qos, "  "),
                # discovery does not carry these to rostool; ROS 2's defaults are what nodes offer
                f"  Lifespan: {qos.get('lifespan', 'Infinite')}",
                f"  Deadline: {qos.get('deadline', 'Infinite')}",
                f"  Liveliness: {str(qos.get('liveliness') or 'automatic').upper()}",
                f"  Liveliness lease duration: {_duration(qos.get('liveliness_lease_duration'))}",
            ]  # fmt: skip
            items.append("\n".join(lines))
    return "".join(f"{item}\n\n" for item in items) if verbose else "\n".join(items) + "\n"


def _duration(seconds: float | None) -> str:
    """A duration as rclpy's Duration prints it."""
    return "Infinite" if seconds is None else f"{round(seconds * 1e9)} nanoseconds"


def service_info_text(found: dict[str, Any], verbose: bool) -> str:
    """ros2 service info: the type, then the clients and servers (counted, or listed with -v)."""
    types = found["types"]
    lines = [f"Type: {types[0] if len(types) == 1 else types}"]
    for title, rows in (("Clients", found["clients"]), ("Services", found["servers"])):
        lines.append(f"{title} count: {len(rows)}")
        for row in rows if verbose else []:
            lines += ["", *_service_endpoint_lines(row)]
        if verbose:
            lines.append("")
    return "\n".join(lines)


def _node_lines(row: dict[str, Any], noun: str, kind: str) -> list[str]:
    namespace, _, node = row["node"].rpartition("/")
    return [
        f"Node name: {node}", f"Node namespace: {namespace or '/'}", f"{noun} type: {row['type']}",
        f"{noun} type hash: {row['type_hash'] or 'UNKNOWN'}", f"Endpoint type: {kind}",
    ]  # fmt: skip


def _service_endpoint_lines(row: dict[str, Any]) -> list[str]:
    """One client or server the way rclpy's ServiceEndpointInfo prints it."""
    endpoints = row["endpoints"]
    role = row["endpoint_type"]
    lines = [*_node_lines(row, "Service", role), f"Endpoint count: {len(endpoints)}"]
    kinds = [kind for kind in ("request", "reply") if kind in endpoints]
    titled = [(_SERVICE_TITLES[(role, kind)], endpoints[kind]) for kind in kinds]
    if len(titled) == 1:
        lines += [f"GID: {titled[0][1]['gid']}", "QoS profile:", *qos_lines(titled[0][1]["qos"], "  ")]
        return lines
    lines += ["GIDs:", *(f" - {title} : {e['gid']}" for title, e in titled), "QoS profiles:"]
    for title, endpoint in titled:
        lines += [f" - {title} :", *qos_lines(endpoint["qos"], "      ")]
    return lines


def qos_lines(qos: dict[str, Any], indent: str) -> list[str]:
    depth = {None: "UNKNOWN", 0: "KEEP_ALL"}.get(qos["depth"], f"KEEP_LAST ({qos['depth']})")
    return [
        f"{indent}Reliability: {str(qos['reliability']).upper()}",
        f"{indent}History (Depth): {depth}",
        f"{indent}Durability: {str(qos['durability']).upper()}",
    ]
