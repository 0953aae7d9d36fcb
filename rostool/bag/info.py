"""`bag info`: facts about a bag from its index or summary only, so it is fast on multi-GB bags.

ROS 1: connection, chunk-info records and chunk headers (as `rosbag info` does; see `ros1_format.py`).
mcap: the summary section through the `mcap` library's `get_summary()`. rosbag2 directory: metadata.yaml.
db3: the topics table plus one GROUP BY over message rows (SQLite skips the blob overflow pages).
Only `--freq` (and an mcap without summary) reads message timestamps.
"""

from __future__ import annotations

import itertools
import statistics
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rostool.bag.open import BagInput, describe, detect, guard, load_metadata
from rostool.errors import RostoolError

NS = 1_000_000_000
FORMAT_NAMES = {"bag": "ROS 1 bag", "rosbag2": "rosbag2 directory", "mcap": "mcap file", "db3": "db3 file"}


@dataclass
class TypeInfo:
    name: str  # as the format names it: `pkg/Name` for ROS 1, `pkg/msg/Name` for ROS 2
    hash: str = ""  # md5 for ROS 1, RIHS01 type hash for ROS 2 where stored


@dataclass
class TopicInfo:
    name: str
    type: str
    count: int
    connections: int = 1
    frequency: float | None = None  # Hz, from the median period (as `rosbag info --freq`)
    serialization: str = "cdr"  # ROS 2: the topic's serialization format


@dataclass
class BagInfo:
    path: str
    format: str  # bag | rosbag2 | mcap | db3
    storage: str  # bag | mcap | sqlite3
    version: str
    size: int
    messages: int
    start_ns: int | None
    end_ns: int | None
    compression: str = "none"
    types: list[TypeInfo] = field(default_factory=list)
    topics: list[TopicInfo] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    chunk_sizes: tuple[int, int] | None = None  # (uncompressed, compressed) bytes when compressed
    note: str = ""
    ros_distro: str = ""  # ROS 2: the distro that recorded it, where stored

    @property
    def ros_version(self) -> int:
        return 1 if self.format == "bag" else 2

    @property
    def duration(self) -> float:
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / NS

    def to_dict(self) -> dict[str, Any]:
        """The `--json` object."""
        result: dict[str, Any] = {
            "path": self.path,
            "format": self.format,
            "storage": self.storage,
            "ros_version": self.ros_version,
            "version": self.version,
            "duration": self.duration,
            "start": None if self.start_ns is None else self.start_ns / NS,
            "end": None if self.end_ns is None else self.end_ns / NS,
            "size": self.size,
            "messages": self.messages,
            "compression": self.compression,
            "types": [{"name": t.name, "hash": t.hash} for t in self.types],
            "topics": [_topic_dict(t) for t in self.topics],
        }
        if self.files:
            result["files"] = self.files
        return result


def _topic_dict(topic: TopicInfo) -> dict[str, Any]:
    entry: dict[str, Any] = {"name": topic.name, "type": topic.type, "count": topic.count}
    if topic.connections > 1:
        entry["connections"] = topic.connections
    if topic.frequency is not None:
        entry["frequency"] = topic.frequency
    return entry


def bag_info(given: str | Path | BagInput, freq: bool = False) -> BagInfo:
    bag = given if isinstance(given, BagInput) else detect(given)
    try:
        with guard(bag.path):  # whatever a damaged file makes the parsers raise: one line naming it
            if bag.kind == "bag":
                return _ros1_info(bag, freq)
            if bag.kind == "rosbag2":
                info = _rosbag2_info(bag)
            elif bag.kind == "mcap":
                info = _mcap_info(bag)
            else:
                info = _db3_info(bag)
    except RostoolError as err:
        text = str(err)
        raise RostoolError(text if text.startswith(str(bag.path)) else f"{bag.path}: {text}") from err
    if freq:
        _ros2_frequencies(bag, info)
    return info


# -- ROS 1 ---------------------------------------------------------------------------------------
def _ros1_info(bag: BagInput, freq: bool) -> BagInfo:
    from rostool.bag import ros1_format as fmt

    with bag.path.open("rb") as handle:
        try:
            index = fmt.read_index(handle)
            times = fmt.read_index_times(handle, index) if freq else {}
        except fmt.FormatError as err:
            if "reindex" in str(err):
                raise RostoolError(f"{bag.path}: {err}") from err
            hint = "if the file was cut short, `rostool bag reindex` can rebuild it"
            raise RostoolError(f"{bag.path}: damaged bag ({err}); {hint}") from err
    counts: Counter[int] = Counter()
    for chunk in index.chunks:
        counts.update(chunk.counts)
    with_messages = [c for c in index.chunks if c.counts]
    start = min(c.start_ns for c in with_messages) if with_messages else None
    end = max(c.end_ns for c in with_messages) if with_messages else None
    types: dict[str, str] = {}
    by_topic: dict[str, list[fmt.Connection]] = {}
    for conn in index.connections.values():
        types.setdefault(conn.datatype, conn.md5sum)
        by_topic.setdefault(conn.topic, []).append(conn)
    topics = []
    for name in sorted(by_topic):
        conns = by_topic[name]
        stamps = sorted(t for c in conns for t in times.get(c.id, [])) if freq else []
        topics.append(
            TopicInfo(
                name, conns[0].datatype, sum(counts[c.id] for c in conns), len(conns), _median_rate(stamps)
            )
        )
    info = BagInfo(
        path=str(bag.path),
        format="bag",
        storage="bag",
        version="2.0",
        size=bag.size,
        messages=sum(counts.values()),
        start_ns=start,
        end_ns=end,
        types=[TypeInfo(name, md5) for name, md5 in sorted(types.items())],
        topics=topics,
    )
    _ros1_compression(info, index.chunk_headers)
    return info


def _ros1_compression(info: BagInfo, headers: list[Any]) -> None:
    if not headers:
        return
    kinds: Counter[str] = Counter(h.compression for h in headers)
    uncompressed: Counter[str] = Counter()
    compressed: Counter[str] = Counter()
    for h in headers:
        uncompressed[h.compression] += h.uncompressed_size
        compressed[h.compression] += h.compressed_size
    parts = []
    for kind, count in sorted(kinds.items(), key=lambda kv: (kv[1], kv[0]), reverse=True):
        if kind == "none":
            parts.append(f"none [{count}/{len(headers)} chunks]")
        else:
            ratio = 100.0 * compressed[kind] / uncompressed[kind] if uncompressed[kind] else 0.0
            parts.append(f"{kind} [{count}/{len(headers)} chunks; {ratio:.2f}%]")
    info.compression = ", ".join(parts)
    if set(kinds) != {"none"}:
        info.chunk_sizes = (sum(uncompressed.values()), sum(compressed.values()))


def _median_rate(stamps: list[int]) -> float | None:
    if len(stamps) < 2:
        return None
    period = statistics.median(b - a for a, b in itertools.pairwise(stamps)) / NS
    return 1.0 / period if period > 0 else None


# -- rosbag2 -------------------------------------------------------------------------------------
def _rosbag2_info(bag: BagInput) -> BagInfo:
    assert bag.metadata is not None
    meta = load_metadata(bag.metadata)
    try:
        count = int(meta.get("message_count", 0))
        start = int(meta["starting_time"]["nanoseconds_since_epoch"])
        duration = int(meta["duration"]["nanoseconds"])
        topics, types = [], {}
        for entry in meta.get("topics_with_message_count") or []:
            topic = entry["topic_metadata"]
            serialization = str(topic.get("serialization_format") or "cdr")
            topics.append(
                TopicInfo(
                    str(topic["name"]),
                    str(topic["type"]),
                    int(entry["message_count"]),
                    serialization=serialization,
                )
            )
            digest = str(topic.get("type_description_hash") or "")
            if not types.get(str(topic["type"])):
                types[str(topic["type"])] = digest
    except (KeyError, TypeError, ValueError) as err:
        raise RostoolError(f"{bag.metadata}: incomplete rosbag2 metadata ({describe_key(err)})") from err
    mode = str(meta.get("compression_mode") or "").lower()
    form = str(meta.get("compression_format") or "")
    compression = f"{form} ({mode})" if mode and mode != "none" and form else "none"
    return BagInfo(
        path=str(bag.path),
        format="rosbag2",
        storage=bag.storage,
        version=str(meta.get("version", "")),
        size=bag.size,
        messages=count,
        start_ns=start if count else None,
        end_ns=start + duration if count else None,
        compression=compression,
        types=[TypeInfo(name, digest) for name, digest in sorted(types.items())],
        topics=sorted(topics, key=lambda t: t.name),
        files=[f.name for f in bag.files],
        ros_distro=str(meta.get("ros_distro") or ""),
    )


def describe_key(err: Exception) -> str:
    return f"missing {err}" if isinstance(err, KeyError) else str(err)


# -- mcap ----------------------------------------------------------------------------------------
def _mcap_info(bag: BagInput) -> BagInfo:
    from mcap.reader import make_reader

    counts: Counter[tuple[int, int]] = Counter()  # (file index, channel id) -> messages
    channels: dict[tuple[int, int], tuple[Any, Any]] = {}  # -> (channel, schema or None)
    chunk_indexes: list[Any] = []
    starts: list[int] = []
    ends: list[int] = []
    profile = ""
    note = ""
    distro = ""
    for number, path in enumerate(bag.files):
        with path.open("rb") as handle:
            try:
                reader = make_reader(handle)
                profile = reader.get_header().profile
                summary = reader.get_summary()
                if summary is not None and summary.metadata_indexes and not distro:
                    distro = _mcap_distro(reader)
            except Exception:  # any damage in the summary section: count by scanning instead
                summary = None
        if summary is not None and summary.statistics is not None:
            stats = summary.statistics
            for cid, count in stats.channel_message_counts.items():
                counts[(number, cid)] += count
            if stats.message_count:
                starts.append(stats.message_start_time)
                ends.append(stats.message_end_time)
            for cid, channel in summary.channels.items():
                channels[(number, cid)] = (channel, summary.schemas.get(channel.schema_id))
            chunk_indexes.extend(summary.chunk_indexes)
        else:
            note = "no summary section (cut short?): counted by scanning; `rostool bag reindex` adds one"
            scanned = _scan_mcap(path)
            channels.update({(number, cid): entry for cid, entry in scanned.channels.items()})
            counts.update({(number, cid): n for cid, n in scanned.counts.items()})
            if scanned.start is not None and scanned.end is not None:
                starts.append(scanned.start)
                ends.append(scanned.end)
    topics: dict[str, TopicInfo] = {}
    types: dict[str, str] = {}
    for key, (channel, schema) in channels.items():
        type_name = schema.name if schema is not None else ""
        digest = channel.metadata.get("topic_type_hash", "") if channel.metadata else ""
        if not types.get(type_name):
            types[type_name] = digest
        topic = topics.setdefault(channel.topic, TopicInfo(channel.topic, type_name, 0))
        topic.count += counts.get(key, 0)
    return BagInfo(
        path=str(bag.path),
        format="mcap",
        storage="mcap",
        version=f"mcap0 (profile {profile or 'none'})",
        size=bag.size,
        messages=sum(counts.values()),
        start_ns=min(starts) if starts else None,
        end_ns=max(ends) if ends else None,
        compression=_mcap_compression(chunk_indexes),
        types=[TypeInfo(name, digest) for name, digest in sorted(types.items()) if name],
        topics=sorted(topics.values(), key=lambda t: t.name),
        files=[f.name for f in bag.files] if len(bag.files) > 1 else [],
        note=note,
        ros_distro=distro,
    )


def _mcap_distro(reader: Any) -> str:
    """rosbag2 stores its metadata.yaml text in an mcap metadata record named `rosbag2`."""
    for record in reader.iter_metadata():
        if record.name == "rosbag2":
            return str(record.metadata.get("ros_distro", ""))
    return ""


def _mcap_compression(chunk_indexes: list[Any]) -> str:
    if not chunk_indexes:
        return "none"
    kinds = Counter(c.compression or "none" for c in chunk_indexes)
    total = len(chunk_indexes)
    parts = []
    for kind, count in kinds.most_common():
        chosen = [c for c in chunk_indexes if (c.compression or "none") == kind]
        raw = sum(c.uncompressed_size for c in chosen)
        packed = sum(c.compressed_size for c in chosen)
        ratio = f"; {100.0 * packed / raw:.2f}%" if kind != "none" and raw else ""
        parts.append(f"{kind} [{count}/{total} chunks{ratio}]")
    return ", ".join(parts)


@dataclass
class _Scan:
    channels: dict[int, tuple[Any, Any]] = field(default_factory=dict)
    counts: Counter[int] = field(default_factory=Counter)
    start: int | None = None
    end: int | None = None


def _scan_mcap(path: Path) -> _Scan:
    """Counts of an mcap without summary, by reading every record (a truncated tail is ignored; data that
    is there but cannot be read, such as a chunk that does not decompress, is an error)."""
    from mcap.exceptions import EndOfFile
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    scan = _Scan()
    schemas: dict[int, Any] = {}
    with path.open("rb") as handle:
        try:
            for record in StreamReader(handle).records:
                if isinstance(record, Message):
                    scan.counts[record.channel_id] += 1
                    t = record.log_time
                    scan.start = t if scan.start is None else min(scan.start, t)
                    scan.end = t if scan.end is None else max(scan.end, t)
                elif isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    scan.channels[record.id] = (record, schemas.get(record.schema_id))
        except EndOfFile:  # cut short: what came before is the bag
            pass
        except Exception as err:  # the mcap library's and the compressors' errors
            readable = sum(scan.counts.values())
            raise RostoolError(
                f"{path}: unreadable data after {readable} messages ({describe(err)}); "
                f"`rostool bag reindex` keeps what can be read"
            ) from err
    return scan


# -- db3 -----------------------------------------------------------------------------------------
def _db3_info(bag: BagInput) -> BagInfo:
    import sqlite3

    counts: Counter[str] = Counter()
    types: dict[str, str] = {}
    topic_types: dict[str, str] = {}
    start: int | None = None
    end: int | None = None
    version = ""
    distro = ""
    for path in bag.files:
        try:
            db = sqlite3.connect(f"file:{path}?mode=ro&immutable=1", uri=True)
        except sqlite3.Error as err:
            raise RostoolError(f"{path}: cannot open database: {describe(err)}") from err
        db.text_factory = lambda raw: raw.decode("utf-8", errors="replace")  # damaged text stays readable
        try:
            tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
            if not {"messages", "topics"} <= tables:
                raise RostoolError(f"{path}: not a rosbag2 database (no messages/topics tables)")
            if "schema" in tables:
                row = db.execute("SELECT schema_version FROM schema").fetchone()
                version = f"sqlite3 schema {row[0]}" if row else version
                if row and "ros_distro" in {r[1] for r in db.execute("PRAGMA table_info(schema)")}:
                    distro = str(db.execute("SELECT ros_distro FROM schema").fetchone()[0] or "")
            columns = {row[1] for row in db.execute("PRAGMA table_info(topics)")}
            hash_column = "type_description_hash" if "type_description_hash" in columns else "''"
            names = {}
            for tid, name, typ, digest in db.execute(f"SELECT id, name, type, {hash_column} FROM topics"):
                if not isinstance(name, str) or not isinstance(typ, str):
                    raise RostoolError(f"{path}: damaged database: topic {tid} has no name or no type")
                names[tid] = name
                topic_types.setdefault(name, typ)
                if not types.get(typ):
                    types[typ] = digest if isinstance(digest, str) else ""
            for tid, count, lo, hi in db.execute(
                "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id"
            ):
                if not all(isinstance(value, int) for value in (count, lo, hi)):
                    raise RostoolError(f"{path}: damaged database: message timestamps are not integers")
                counts[names.get(tid, f"<topic id {tid}>")] += count
                start = lo if start is None else min(start, lo)
                end = hi if end is None else max(end, hi)
        except sqlite3.Error as err:
            raise RostoolError(f"{path}: cannot read database: {describe(err)}") from err
        finally:
            db.close()
    return BagInfo(
        path=str(bag.path),
        format="db3",
        storage="sqlite3",
        version=version or "sqlite3",
        size=bag.size,
        messages=sum(counts.values()),
        start_ns=start,
        end_ns=end,
        types=[TypeInfo(name, digest) for name, digest in sorted(types.items())],
        topics=[TopicInfo(name, topic_types.get(name, ""), counts[name]) for name in sorted(topic_types)],
        files=[f.name for f in bag.files] if len(bag.files) > 1 else [],
        ros_distro=distro,
    )


def _ros2_frequencies(bag: BagInput, info: BagInfo) -> None:
    from rostool.bag.reader import BagReader

    stamps: dict[str, list[int]] = {}
    with BagReader([bag]) as reader:
        for conn, timestamp, _data in reader.messages():
            stamps.setdefault(conn.topic, []).append(timestamp)
    for topic in info.topics:
        topic.frequency = _median_rate(sorted(stamps.get(topic.name, [])))


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


def format_text(info: BagInfo, verbose: bool = False, topic_name: bool = False) -> str:
    """Human output laid out as the bag's own tool prints it: `rosbag info` for ROS 1 bags, `ros2 bag
    info` for rosbag2 directories, .mcap and .db3 files (see `rosbag2_info.format_ros2`).

    `topic_name`: only the topic names, one a line (`ros2 bag info -t`); `verbose`: ROS 2 bags count the
    requests and responses of each service (`ros2 bag info -v`, reads the service event messages)."""
    from rostool.bag import rosbag2_info

    if topic_name:
        return rosbag2_info.topic_names(info)
    if info.ros_version == 2:
        counts = rosbag2_info.count_service_events(info.path, info) if verbose else None
        return rosbag2_info.format_ros2(info, verbose, counts)
    return format_rosbag(info)


def format_rosbag(info: BagInfo) -> str:
    """`rosbag info`'s layout (ROS 2 bags add `storage:` and use ROS 2 type names)."""
    rows: list[tuple[str, str]] = [("path", info.path), ("version", info.version)]
    if info.ros_version == 2:
        rows.append(("storage", f"{info.storage} ({FORMAT_NAMES[info.format]})"))
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
