"""`bag info` of rosbag2 bags in `ros2 bag info`'s layout (rosbag2_py's format_bag_metadata, Jazzy).

Labels are padded to 19 columns ("Topic information: "), continuation lines indented as far; service
event topics (`NAME/_service_event` of type `pkg/srv/T_Event`) are listed as services, not topics, and
left out of `Messages:`. Times are local (TZ), with nanoseconds; sizes in B/KiB/MiB/GiB/TiB.
`-v` counts requests and responses per service by reading its events (distinct client and sequence
number per kind); `-t` prints the topic names only.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass

from rostool.bag.model import NS, BagInfo, TopicInfo

INDENT = " " * 19
SERVICE_INDENT = " " * len("Service information: ")
SERVICE_EVENT_SUFFIX = "/_service_event"


@dataclass
class ServiceCounts:
    requests: int = 0
    responses: int = 0


def is_service_event(name: str, type_name: str) -> bool:
    return "/srv/" in type_name and type_name.endswith("_Event") and name.endswith(SERVICE_EVENT_SUFFIX)


def _services(info: BagInfo) -> list[TopicInfo]:
    return [t for t in info.topics if is_service_event(t.name, t.type)]


def _topics(info: BagInfo) -> list[TopicInfo]:
    return [t for t in info.topics if not is_service_event(t.name, t.type)]


def topic_names(info: BagInfo) -> str:
    """`ros2 bag info -t`: one topic name a line, services left out."""
    return "\n".join(t.name for t in _topics(info))


def file_size(size: int) -> str:
    value = float(size)
    units = ("B", "KiB", "MiB", "GiB", "TiB")
    index = 0
    while value >= 1024 and index < len(units) - 1:
        value /= 1024
        index += 1
    return f"{value:.0f} {units[index]}" if index == 0 else f"{value:.1f} {units[index]}"


def _seconds(ns: int) -> str:
    secs, frac = divmod(ns, NS)
    return f"{secs}.{frac:09d}"


def time_point(ns: int) -> str:
    secs, frac = divmod(ns, NS)
    try:
        local = time.localtime(secs)
        date = time.strftime("%b ", local) + f"{local.tm_mday:>2}" + time.strftime(" %Y %H:%M:%S", local)
    except (OverflowError, ValueError, OSError):  # a damaged or made-up time stamp
        date = "out of range"
    return f"{date}.{frac:09d} ({_seconds(ns)})"


def _lines(first_label: str, items: Iterable[str], indent: str) -> list[str]:
    items = list(items)
    if not items:
        return [first_label]
    return [first_label + items[0], *(indent + item for item in items[1:])]


def format_ros2(
    info: BagInfo,
    verbose: bool = False,
    service_counts: dict[str, ServiceCounts] | None = None,
    sort: str | None = None,
) -> str:
    """The text `ros2 bag info BAG` prints (`verbose`: with request/response counts per service; topics come
    in `info`'s order, see `info.sort_topics`)."""
    start = info.start_ns or 0
    duration = (info.end_ns or start) - start
    topics = _topics(info)
    services = _services(info)
    files = info.files or [info.path]
    lines = [
        "",
        *_lines("Files:             ", files, INDENT),
        f"Bag size:          {file_size(info.size)}",
        f"Storage id:        {info.storage}",
        f"ROS Distro:        {info.ros_distro or 'unknown'}",
        f"Duration:          {_seconds(duration)}s",
        f"Start:             {time_point(start)}",
        f"End:               {time_point(start + duration)}",
        f"Messages:          {sum(t.count for t in topics)}",
    ]
    lines += _lines(
        "Topic information: ",
        (
            f"Topic: {t.name} | Type: {t.type} | Count: {t.count} | Serialization Format: {t.serialization}"
            for t in topics
        ),
        INDENT,
    )
    lines.append(f"Service:           {len(services)}")
    if verbose and sort == "count":  # rosbag2 sorts services by requests + responses when it counts them
        counted = service_counts or {}
        services.sort(key=lambda s: (c := counted.get(s.name, ServiceCounts())).requests + c.responses)
    rows = []
    for service in services:
        name = service.name[: -len(SERVICE_EVENT_SUFFIX)]
        type_name = service.type[: -len("_Event")]
        if verbose:
            counts = (service_counts or {}).get(service.name, ServiceCounts())
            count = f"Request Count: {counts.requests} | Response Count: {counts.responses}"
        else:
            count = f"Event Count: {service.count}"
        rows.append(
            f"Service: {name} | Type: {type_name} | {count} | Serialization Format: {service.serialization}"
        )
    lines += _lines("Service information: ", rows, SERVICE_INDENT)
    return "\n".join(lines)


def count_service_events(path: str, info: BagInfo, distro: str | None = None) -> dict[str, ServiceCounts]:
    """Requests and responses per service event topic: distinct (client, sequence number) per kind."""
    from rostool.bag.reader import BagReader

    wanted = [t.name for t in _services(info)]
    if not wanted:
        return {}
    seen: dict[str, tuple[set[tuple[bytes, int]], set[tuple[bytes, int]]]] = {}
    args = (distro,) if distro else ()
    with BagReader([path], *args) as reader:
        conns = reader.select(wanted)
        for conn, _stamp, data in reader.messages(conns):
            event = reader.deserialize(data, conn).info
            key = (bytes(event.client_gid), int(event.sequence_number))
            requests, responses = seen.setdefault(conn.topic, (set(), set()))
            (requests if int(event.event_type) in (0, 1) else responses).add(key)
    return {topic: ServiceCounts(len(req), len(resp)) for topic, (req, resp) in seen.items()}
