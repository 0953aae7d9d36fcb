"""An indexed .mcap read chunk by chunk into per-channel batches of raw messages, for columnar export.

The mcap library (and rosbags' reader on top of it) makes a Python object per record, which caps reading at
about 130,000 messages a second; export needs only each message's log time and the offset of its bytes. This
reader decompresses a chunk (no more than the size its header declares), walks its records once, and hands
out per channel the chunk buffer with the start, size and log time of each message: what the columnar decoder
gathers from directly. It serves only what it can serve in the order a time-ordered read gives per channel:
an indexed file whose chunks do not overlap in time (what rosbag2 and the mcap CLI write); anything else
(`plan` returns None) is read the usual way.
"""

from __future__ import annotations

import struct
from collections.abc import Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from rostool.bag import export_cost
from rostool.bag.bounded import inflate
from rostool.errors import RostoolError

_MESSAGE = 0x05
_CHUNK = 0x06
_RECORD = struct.Struct("<BQ")
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time
_CHUNK_HEAD = struct.Struct("<QQQI")  # start time, end time, uncompressed size, uncompressed crc
_MESSAGE_INDEX_HEAD = 1 + 8 + 2 + 4  # a MessageIndex record's opcode, length, channel id, records' length


@dataclass
class ChannelBatch:
    """Messages of one channel from one chunk, in log-time order: `buffer[starts[i]:starts[i] + sizes[i]]`."""

    channel_id: int
    buffer: bytes
    starts: np.ndarray
    sizes: np.ndarray
    log_times: np.ndarray


@dataclass(frozen=True)
class ChunkPlan:
    """The chunks to read, in file order (which is log-time order: they do not overlap), and the wanted
    channels of each file, with the caller's object (a connection) for each."""

    chunks: tuple[tuple[Path, int, int], ...]  # (file, offset, length) of each Chunk record
    channels: dict[Path, dict[int, Any]]
    # each chunk's estimated export seconds (export_cost's rates, its wanted messages counted from its
    # message indexes); empty when a file has none: chunks are then weighed by their bytes
    weights: tuple[float, ...] = ()

    def share(self, piece: int, pieces: int) -> ChunkPlan:
        """The `piece`-th of `pieces` consecutive runs of chunks of about equal work (some may be empty).
        Work, not bytes: a bag whose costly topic (TFMessage, decoded one by one) crowds one part of the
        file would give one piece most of it."""
        weights = (
            self.weights
            if len(self.weights) == len(self.chunks)
            else tuple(float(length) for _path, _offset, length in self.chunks)
        )
        total = sum(weights)
        start = end = 0
        done = 0.0
        for index, weight in enumerate(weights):
            # a chunk belongs to the piece its middle falls in
            owner = min(pieces - 1, int((done + weight / 2) * pieces / total)) if total else 0
            done += weight
            if owner < piece:
                start = index + 1
            if owner <= piece:
                end = index + 1
        return ChunkPlan(self.chunks[start:end], self.channels, weights[start:end])


def plan(paths: Sequence[Path], wanted: Mapping[tuple[str, str], Any]) -> ChunkPlan | None:
    """The chunks of `paths` holding the `wanted` (topic, message type) channels, or None when this reader
    cannot give the per-channel time order (no summary or chunk index, chunks overlapping in time, an
    unknown compression)."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    chunks: list[tuple[Path, int, int]] = []
    channels: dict[Path, dict[int, Any]] = {}
    weights: list[float] | None = []
    last_end = -1
    for path in paths:
        try:
            with path.open("rb") as handle:
                summary = make_reader(handle).get_summary()
        except (McapError, OSError, ValueError, struct.error):
            return None
        if summary is None or not summary.chunk_indexes:
            return None
        channels[path] = {}
        per_message: dict[int, float] = {}
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id)
            target = wanted.get((channel.topic, schema.name if schema else ""))
            if target is not None:
                channels[path][channel.id] = target
                flat = schema is not None and export_cost.is_flat(schema.encoding, schema.data)
                per_message[channel.id] = export_cost.FLAT_MESSAGE if flat else export_cost.NESTED_MESSAGE
        for index in sorted(summary.chunk_indexes, key=lambda index: index.chunk_start_offset):
            if index.message_start_time < last_end or index.compression not in ("", "zstd", "lz4"):
                return None
            last_end = index.message_end_time
            chunks.append((path, index.chunk_start_offset, index.chunk_length))
            counts = _indexed_counts(index)
            if weights is not None and counts is not None:
                messages = sum(count * per_message.get(channel, 0.0) for channel, count in counts.items())
                weights.append(messages + index.uncompressed_size * export_cost.BYTE)
            else:
                weights = None
    return ChunkPlan(tuple(chunks), channels, tuple(weights or ()))


def _indexed_counts(index: Any) -> dict[int, int] | None:
    """Each channel's message count in a chunk, from the sizes of its MessageIndex records (which follow
    the chunk, one per channel: opcode, length, channel id, records length, 16 bytes a message), without
    reading them; None for a chunk written without message indexes."""
    offsets = sorted(index.message_index_offsets.items(), key=lambda pair: pair[1])
    if not offsets or not index.message_index_length:
        return None
    first = offsets[0][1]
    ends = [offset for _channel, offset in offsets[1:]] + [first + index.message_index_length]
    return {
        channel: max(0, (end - offset - _MESSAGE_INDEX_HEAD) // 16)
        for (channel, offset), end in zip(offsets, ends, strict=True)
    }


def batches(chunk_plan: ChunkPlan) -> Iterator[tuple[Any, ChannelBatch]]:
    """The messages of the wanted channels, chunk by chunk, each channel's in log-time order."""
    handles: dict[Path, BinaryIO] = {}
    try:
        for path, offset, length in chunk_plan.chunks:
            handle = handles.get(path)
            if handle is None:
                handle = handles[path] = path.open("rb")
            wanted = chunk_plan.channels[path]
            records = _chunk_records(handle, offset, length, path)
            for batch in _split(records, wanted.keys(), path):
                yield wanted[batch.channel_id], batch
    finally:
        for handle in handles.values():
            handle.close()


def _chunk_records(handle: BinaryIO, offset: int, length: int, path: Path) -> bytes:
    handle.seek(offset)
    raw = handle.read(length)
    if len(raw) != length or raw[0] != _CHUNK:
        raise RostoolError(f"{path}: a chunk the index points to is not there; try `rostool bag reindex`")
    try:
        _start, _end, uncompressed_size, _crc = _CHUNK_HEAD.unpack_from(raw, 9)
        pos = 9 + _CHUNK_HEAD.size
        (name_length,) = struct.unpack_from("<I", raw, pos)
        compression = raw[pos + 4 : pos + 4 + name_length].decode("ascii", "replace")
        pos += 4 + name_length
        (records_length,) = struct.unpack_from("<Q", raw, pos)
    except struct.error as err:
        raise RostoolError(f"{path}: a chunk's header is cut short; try `rostool bag reindex`") from err
    records = raw[pos + 8 : pos + 8 + records_length]
    try:
        # no more than the declared size: a chunk that declares little and inflates to gigabytes stops there
        data = inflate(compression, records, uncompressed_size) if compression else records
    except RostoolError as err:
        raise RostoolError(f"{path}: {err}", err.exit_code) from err
    if len(data) != uncompressed_size:
        raise RostoolError(
            f"{path}: a chunk holds {len(data)} bytes where its header says {uncompressed_size};"
            " try `rostool bag reindex`"
        )
    return bytes(data)


def _split(data: bytes, channels: Collection[int], path: Path) -> Iterator[ChannelBatch]:
    """One walk over a chunk's records; the Message records of `channels` grouped by channel."""
    found: dict[int, tuple[list[int], list[int], list[int]]] = {}
    unpack_record, unpack_head = _RECORD.unpack_from, _MESSAGE_HEAD.unpack_from
    pos, end = 0, len(data)
    head = _RECORD.size + _MESSAGE_HEAD.size
    run: int | None = None
    tried = False
    while pos + _RECORD.size <= end:
        if not tried and data[pos] == _MESSAGE:
            tried = True  # once per chunk, at its first message
            run = _uniform_run(data, pos)
            if run is not None:  # the rest of the chunk: one channel's messages of one size
                break
        opcode, length = unpack_record(data, pos)
        if opcode == _MESSAGE and length >= _MESSAGE_HEAD.size:
            channel, _seq, log_time, _pub = unpack_head(data, pos + _RECORD.size)
            if channel in channels:
                lists = found.get(channel)
                if lists is None:
                    lists = found[channel] = ([], [], [])
                lists[0].append(pos + head)
                lists[1].append(length - _MESSAGE_HEAD.size)
                lists[2].append(log_time)
        pos += _RECORD.size + length
    if run is not None:
        yield from _batches_of(data, found)  # none, as a rule: records before the first message are not
        yield from _run_batch(data, pos, run, channels)
        return
    if pos != end:
        raise RostoolError(f"{path}: a chunk's last record runs past its end; try `rostool bag reindex`")
    yield from _batches_of(data, found)


def _batches_of(
    data: bytes, found: dict[int, tuple[list[int], list[int], list[int]]]
) -> Iterator[ChannelBatch]:
    for channel, (starts, sizes, times) in found.items():
        log_times = np.array(times, dtype=np.int64)
        starts_array = np.array(starts, dtype=np.int64)
        sizes_array = np.array(sizes, dtype=np.int64)
        if len(log_times) > 1 and (np.diff(log_times) < 0).any():
            order = np.argsort(log_times, kind="stable")
            log_times, starts_array, sizes_array = log_times[order], starts_array[order], sizes_array[order]
        yield ChannelBatch(channel, data, starts_array, sizes_array, log_times)


def _uniform_run(data: bytes, pos: int) -> int | None:
    """The number of records from `pos` to the chunk's end when all are Message records of one channel and
    one length (a chunk of a single fixed-size topic: read without a Python step per message)."""
    length = _RECORD.unpack_from(data, pos)[1]
    stride = _RECORD.size + length
    if length < _MESSAGE_HEAD.size or (len(data) - pos) % stride:
        return None
    count = (len(data) - pos) // stride
    records = np.frombuffer(data, dtype=np.uint8, offset=pos).reshape(count, stride)
    channel = records[0, 9:11]
    if not (
        (records[:, 0] == _MESSAGE).all()
        and (records[:, 1:9] == records[0, 1:9]).all()
        and (records[:, 9:11] == channel).all()
    ):
        return None
    return count


def _run_batch(data: bytes, pos: int, count: int, channels: Collection[int]) -> Iterator[ChannelBatch]:
    length = _RECORD.unpack_from(data, pos)[1]
    stride = _RECORD.size + length
    channel = int.from_bytes(data[pos + 9 : pos + 11], "little")
    if channel not in channels:
        return
    records = np.frombuffer(data, dtype=np.uint8, offset=pos).reshape(count, stride)
    log_times = np.ascontiguousarray(records[:, 15:23]).view("<u8").ravel().astype(np.int64)
    starts = pos + np.arange(count, dtype=np.int64) * stride + _RECORD.size + _MESSAGE_HEAD.size
    sizes = np.full(count, length - _MESSAGE_HEAD.size, dtype=np.int64)
    if count > 1 and (np.diff(log_times) < 0).any():
        order = np.argsort(log_times, kind="stable")
        log_times, starts = log_times[order], starts[order]
    yield ChannelBatch(channel, data, starts, sizes, log_times)
