"""`bag info` of .mcap files: the summary section through the `mcap` library's `get_summary()`; a file
without one (its writer was killed) is counted by reading every record."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rostool.bag.failures import describe
from rostool.bag.model import BagInfo, BagInput, TopicInfo, TypeInfo
from rostool.errors import RostoolError


def mcap_info(bag: BagInput, _freq: bool = False) -> BagInfo:
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
