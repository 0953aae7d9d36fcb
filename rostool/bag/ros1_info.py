"""`bag info` of a ROS 1 bag from its connection, chunk-info records and chunk headers alone, as `rosbag
info` reads it (see `ros1_format.py`): fast on multi-GB bags, and nothing heavy imported."""

from __future__ import annotations

import itertools
import statistics
from collections import Counter
from typing import Any

from rostool.bag import ros1_format as fmt
from rostool.bag.model import NS, BagInfo, BagInput, TopicInfo, TypeInfo
from rostool.errors import RostoolError


def ros1_info(bag: BagInput, freq: bool = False) -> BagInfo:
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
                name, conns[0].datatype, sum(counts[c.id] for c in conns), len(conns), median_rate(stamps)
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


def median_rate(stamps: list[int]) -> float | None:
    if len(stamps) < 2:
        return None
    period = statistics.median(b - a for a, b in itertools.pairwise(stamps)) / NS
    return 1.0 / period if period > 0 else None
