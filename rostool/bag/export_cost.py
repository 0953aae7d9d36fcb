"""What exporting a bag will cost, estimated before any message is read, to decide how `bag export` spreads
its work: whether worker processes pay, and whether a big indexed .mcap is cut into pieces (export_many.py).

The estimate is CPU seconds on one core. For an indexed .mcap it comes from the file's summary (cheap: the
end of the file): each wanted channel's message count times the cost of its type, plus its bytes. Measured
(bench/RESULTS.md, bench_export_ray.py): a type whose fields are numbers, strings, fixed or primitive arrays
(Imu, Odometry, JointState...) decodes column-wise, ~0.5 us a message plus ~1 ns a byte written; a type with
sequences of messages (tf2_msgs/TFMessage, a MarkerArray) or a schema that is not a .msg text is
deserialized message by message, ~25 us a message (50 us while a reference cycle kept each batch alive
for Python's full collections). Any other bag (.bag, .db3, object storage) counts its
bytes at the rate that made 64 MiB worth a second worker before (`many.PARALLEL_FROM_BYTES`).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from pathlib import Path
from typing import Any

FLAT_MESSAGE = 0.5e-6  # seconds per message of a column-wise type
NESTED_MESSAGE = 25e-6  # seconds per message decoded one by one (100,000 TFMessage: 2.2-2.6 s CPU)
BYTE = 1e-9  # seconds per byte of messages (copied, compressed, written)
PARALLEL_FROM = 1.5  # seconds of work from which worker processes pay off (their start-up is ~0.5 s)
PIECE_SECONDS = 3.0  # the least work a piece of a cut bag holds: its worker's start-up and the join pay off

_PRIMITIVES = frozenset((
    "bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
    "float32", "float64", "string", "wstring",
))  # fmt: skip
_SECONDS_PER_BYTE_ELSEWHERE = PARALLEL_FROM / (64 * 1024 * 1024)


def seconds(path: Path | Any, topics: Sequence[str] = ()) -> float:
    """The estimated CPU seconds of exporting the bag at `path` (its `topics`, or all)."""
    if not isinstance(path, Path):
        return 0.0  # in object storage: not worth a request
    files = sorted(path.glob("*.mcap")) if path.is_dir() else [path] if path.suffix == ".mcap" else []
    total = 0.0
    for file in files:
        cost = _mcap_seconds(file, set(topics))
        if cost is None:
            return _by_size(path)
        total += cost
    return total if files else _by_size(path)


def is_flat(schema_encoding: str, text: bytes) -> bool:
    """Whether a .msg definition (with its dependencies, as .mcap schemas hold them) has no sequence or array
    of messages: what the columnar decoder reads without a Python object per message."""
    if schema_encoding not in ("ros2msg", "ros1msg"):
        return False
    for line in text.decode("utf-8", "replace").splitlines():
        words = line.split("#", 1)[0].split()
        if len(words) < 2 or words[0] == "MSG:" or "[" not in words[0]:
            continue
        element = words[0][: words[0].index("[")].split("<=", 1)[0]
        if element not in _PRIMITIVES:
            return False
    return True


def _mcap_seconds(file: Path, topics: set[str]) -> float | None:
    """None when the file has no summary with message counts (it is then read message by message)."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    try:
        with file.open("rb") as handle:
            summary = make_reader(handle).get_summary()
    except (McapError, OSError, ValueError, KeyError, struct.error):  # damaged: the export itself says so
        return None
    if summary is None or summary.statistics is None or not summary.chunk_indexes:
        return None
    counts = summary.statistics.channel_message_counts
    messages = 0.0
    wanted = 0
    for channel in summary.channels.values():
        if topics and channel.topic not in topics:
            continue
        count = counts.get(channel.id, 0)
        wanted += count
        schema = summary.schemas.get(channel.schema_id)
        flat = schema is not None and is_flat(schema.encoding, schema.data)
        messages += count * (FLAT_MESSAGE if flat else NESTED_MESSAGE)
    everything = sum(counts.values()) or 1
    size = sum(index.uncompressed_size for index in summary.chunk_indexes) * wanted / everything
    return messages + size * BYTE


def _by_size(path: Path) -> float:
    try:
        size = (
            sum(entry.stat().st_size for entry in path.rglob("*") if entry.is_file())
            if path.is_dir()
            else path.stat().st_size
        )
    except OSError:
        return 0.0
    return size * _SECONDS_PER_BYTE_ELSEWHERE
