"""`bag info`: facts about a bag from its index or summary only, so it is fast on multi-GB bags.

Each format's facts come from its module in the format table (`formats.py`): ROS 1 from the connection,
chunk-info records and chunk headers (`ros1_info`), mcap from its summary section (`mcap_info`), a rosbag2
directory from metadata.yaml (`rosbag2_metadata`), db3 from its topics table and one GROUP BY (`db3_info`).
Only `--freq` (and an mcap without summary) reads message timestamps. Rendered here in `rosbag info`'s
layout, or in `ros2 bag info`'s (`rosbag2_info.py`).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from rostool.bag.failures import guard
from rostool.bag.formats import FORMATS
from rostool.bag.model import NS, BagInfo, BagInput
from rostool.bag.open import detect
from rostool.bag.ros1_info import median_rate
from rostool.errors import RostoolError


def bag_info(given: str | Path | BagInput, freq: bool = False) -> BagInfo:
    bag = given if isinstance(given, BagInput) else detect(given)
    fmt = FORMATS[bag.kind]
    try:
        with guard(bag.path):  # whatever a damaged file makes the parsers raise: one line naming it
            info = fmt.info(bag, freq)
    except RostoolError as err:
        text = str(err)
        raise RostoolError(text if text.startswith(str(bag.path)) else f"{bag.path}: {text}") from err
    if freq and fmt.ros_version == 2:  # ROS 1's index holds the times; ROS 2 bags are read for them
        _ros2_frequencies(bag, info)
    return info


def _ros2_frequencies(bag: BagInput, info: BagInfo) -> None:
    from rostool.bag.reader import BagReader

    stamps: dict[str, list[int]] = {}
    with BagReader([bag]) as reader:
        for conn, timestamp, _data in reader.messages():
            stamps.setdefault(conn.topic, []).append(timestamp)
    for topic in info.topics:
        topic.frequency = median_rate(sorted(stamps.get(topic.name, [])))


SORT_KEYS = ("name", "type", "count")  # rosbag2's `ros2 bag info --sort` methods, each ascending


def sort_topics(info: BagInfo, by: str) -> None:
    """Order the topics as `ros2 bag info --sort BY` does: ascending by name, type or message count (a
    stable sort: ties keep the bag's order)."""
    if by not in SORT_KEYS:
        raise RostoolError(f"--sort {by}: choose one of {', '.join(SORT_KEYS)}")
    info.topics.sort(key=lambda t: getattr(t, by))


# -- rendering -----------------------------------------------------------------------------------
def _percent(part: int, whole: int) -> str:
    """rosbag's compression ratio; a damaged chunk header may declare 0 bytes uncompressed."""
    return f"{100.0 * part / whole:.2f}%" if whole else "n/a"


def _size(size: float) -> str:
    for suffix in ("KB", "MB", "GB", "TB", "PB", "EB", "ZB", "YB"):
        size /= 1024.0
        if size < 1024.0:
            return f"{size:.1f} {suffix}"
    return "-"


def _frequency(freq: float) -> str:
    for suffix in ("Hz", "kHz", "MHz", "GHz", "THz"):
        if freq < 1000.0:
            return f"{freq:.1f} {suffix}"
        freq /= 1000.0
    return "-"


def _stamp(ns: int) -> str:
    secs = ns / NS
    fraction = f"{secs - int(secs):.2f}"[1:]
    try:
        when = time.strftime("%b %d %Y %H:%M:%S", time.localtime(secs)) + fraction
    except (OverflowError, ValueError, OSError):  # a damaged or made-up time stamp
        when = "out of range"
    return f"{when} ({secs:.2f})"


def _duration(duration: float) -> str:
    mins, hrs = int(duration / 60), int(duration / 3600)
    if hrs > 0:
        return f"{hrs}hr {mins % 60}:{int(duration % 60):02d}s ({int(duration)}s)"
    if mins > 0:
        return f"{mins}:{int(duration % 60):02d}s ({int(duration)}s)"
    return f"{duration:.1f}s"


def format_text(
    info: BagInfo, verbose: bool = False, topic_name: bool = False, sort: str | None = None
) -> str:
    """Human output laid out as the bag's own tool prints it: `rosbag info` for ROS 1 bags, `ros2 bag
    info` for rosbag2 directories, .mcap and .db3 files (see `rosbag2_info.format_ros2`).

    `topic_name`: only the topic names, one a line (`ros2 bag info -t`); `verbose`: ROS 2 bags count the
    requests and responses of each service (`ros2 bag info -v`, reads the service event messages)."""
    from rostool.bag import rosbag2_info

    if topic_name:
        return rosbag2_info.topic_names(info)
    if info.ros_version == 2:
        counts = rosbag2_info.count_service_events(info.path, info) if verbose else None
        return rosbag2_info.format_ros2(info, verbose, counts, sort)
    return format_rosbag(info)


def format_rosbag(info: BagInfo) -> str:
    """`rosbag info`'s layout (ROS 2 bags add `storage:` and use ROS 2 type names)."""
    rows: list[tuple[str, str]] = [("path", info.path), ("version", info.version)]
    if info.ros_version == 2:
        rows.append(("storage", f"{info.storage} ({FORMATS[info.format].label})"))
    if info.start_ns is None and not info.topics:
        rows.append(("size", _size(info.size)))
        return _layout(rows, info)
    if info.start_ns is not None and info.end_ns is not None:
        rows += [
            ("duration", _duration(info.duration)),
            ("start", _stamp(info.start_ns)),
            ("end", _stamp(info.end_ns)),
        ]
    rows += [("size", _size(info.size)), ("messages", str(info.messages)), ("compression", info.compression)]
    if info.chunk_sizes:
        raw, packed = info.chunk_sizes
        raw_s, packed_s = _size(raw), _size(packed)
        width = max(len(raw_s), len(packed_s))
        if info.duration > 0:
            raw_r, packed_r = _size(raw / info.duration), _size(packed / info.duration)
            rate = max(len(raw_r), len(packed_r))
            rows.append(("uncompressed", f"{raw_s:>{width}} @ {raw_r:>{rate}}/s"))
            rows.append(
                ("compressed", f"{packed_s:>{width}} @ {packed_r:>{rate}}/s ({_percent(packed, raw)})")
            )
        else:
            rows += [("uncompressed", f"{raw_s:>{width}}"), ("compressed", f"{packed_s:>{width}}")]
    if info.types:
        type_width = max(len(t.name) for t in info.types)
        for i, typ in enumerate(info.types):
            text = f"{typ.name:<{type_width}} [{typ.hash}]" if typ.hash else typ.name
            rows.append(("types" if i == 0 else "", text))
    if info.topics:
        name_width = max(len(t.name) for t in info.topics)
        type_width = max(len(t.type) for t in info.topics)
        count_width = max(len(str(t.count)) for t in info.topics)
        freqs = [_frequency(t.frequency) for t in info.topics if t.frequency is not None]
        freq_width = max((len(f) for f in freqs), default=0)
        for i, topic in enumerate(info.topics):
            text = f"{topic.name:<{name_width}}   {topic.count:>{count_width}} "
            text += "msgs" if topic.count > 1 else "msg "
            if topic.frequency is not None:
                text += f" @ {_frequency(topic.frequency):>{freq_width}}"
            else:
                text += f"   {'':>{freq_width}}"
            text += f" : {topic.type:<{type_width}}"
            if topic.connections > 1:
                text += f" ({topic.connections} connections)"
            rows.append(("topics" if i == 0 else "", text))
    if info.files:
        for i, name in enumerate(info.files):
            rows.append(("files" if i == 0 else "", name))
    return _layout(rows, info)


def _layout(rows: list[tuple[str, str]], info: BagInfo) -> str:
    if info.note:
        rows.append(("note", info.note))
    width = max(len(name) for name, _ in rows) + 1
    lines = [f"{(name + ':') if name else '':<{width}} {value}" for name, value in rows]
    return "\n".join(lines).rstrip()


def to_rosbag_yaml(info: BagInfo) -> dict[str, Any]:
    """The `--yaml` mapping: `rosbag info --yaml`'s keys (ROS 2 bags add format/storage, hash for md5)."""
    version: Any = info.version
    if info.ros_version == 1:
        version = float(info.version)  # rosbag prints `version: 2.0`, which YAML reads as a number
    elif info.version.isdigit():
        version = int(info.version)
    data: dict[str, Any] = {"path": info.path, "version": version}
    if info.ros_version == 2:
        data["format"] = info.format
        data["storage"] = info.storage
    if info.start_ns is not None or info.topics:
        data["duration"] = round(info.duration, 6)
        data["start"] = round((info.start_ns or 0) / NS, 6)
        data["end"] = round((info.end_ns or 0) / NS, 6)
    data["size"] = info.size
    if info.ros_version == 1 and info.start_ns is None and not info.topics:
        data["indexed"] = False  # what `rosbag info --yaml` says of a bag without chunks
        return data
    data["messages"] = info.messages
    data["indexed"] = not info.note
    data["compression"] = info.compression.split(" ")[0]
    if info.chunk_sizes:
        data["uncompressed"], data["compressed"] = info.chunk_sizes
    key = "md5" if info.ros_version == 1 else "hash"
    data["types"] = [{"type": t.name, key: t.hash} for t in info.types]
    topics = []
    for topic in info.topics:
        entry: dict[str, Any] = {"topic": topic.name, "type": topic.type, "messages": topic.count}
        if topic.connections > 1:
            entry["connections"] = topic.connections
        if topic.frequency is not None:
            entry["frequency"] = round(topic.frequency, 4)
        topics.append(entry)
    data["topics"] = topics
    return data
