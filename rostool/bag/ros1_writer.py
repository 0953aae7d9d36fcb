"""A streaming ROS 1 bag (v2.0) writer for `bag record`, built to survive its own death.

rosbags' rosbag1.Writer keeps each chunk in memory until it holds 1 MB, so a recorder killed with SIGKILL
loses everything of a slow topic, and a failed write leaves a file without index. This writer does what
rosbag's C++ recorder does: uncompressed chunks are streamed to the file as messages arrive (the chunk
header's sizes are patched when the chunk closes), so whatever `flush()` pushed to the OS survives a
SIGKILL and `rostool bag reindex` recovers it. Compressed chunks are kept in memory and closed at the size
threshold or when older than `max_chunk_age` seconds. A write error (disk full, file size limit) never
leaves an unreadable file: `close()` cuts the file back to the last complete record and writes the index
for what is on disk.
"""

from __future__ import annotations

import bz2
import os
import struct
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

from rostool.bag import ros1_format as fmt

CHUNK_THRESHOLD = 768 * 1024  # rosbag record's default
_MSG = struct.Struct("<II4sI5sII5sIII")  # a message record: header (op, conn, time) and data length
_MSG_HEADER_LEN = 4 + 4 + 4 + 5 + 4 + 4 + 5 + 8
_INDEX_ENTRY = struct.Struct("<III")
_U32 = struct.Struct("<I")
_BUFFER = 1 << 20
_DIRECT = 64 * 1024  # payloads at least this big are written straight from the received bytes


def _lz4(data: bytes) -> bytes:
    import lz4.frame

    return bytes(lz4.frame.compress(data))


COMPRESSORS: dict[str, Callable[[bytes], bytes]] = {
    "bz2": lambda data: bz2.compress(data, 9),
    "lz4": _lz4,
}


class WriteFailed(OSError):
    """Writing to the bag failed; `close()` still leaves a valid file with what reached the disk."""


@dataclass
class _Chunk:
    pos: int  # file offset of the chunk record
    data_pos: int  # file offset of its data (uncompressed, streamed chunks)
    size: int = 0  # bytes of (uncompressed) chunk data so far
    start: int = 2**63 - 1
    end: int = 0
    opened: float = field(default_factory=time.monotonic)
    index: dict[int, bytearray] = field(default_factory=dict)  # conn -> (sec, nsec, offset) entries
    counts: dict[int, int] = field(default_factory=dict)
    ends: list[tuple[int, int, int, int]] = field(default_factory=list)  # (offset, end, conn, time)
    memory: bytearray = field(default_factory=bytearray)  # data of a compressed chunk


@dataclass(frozen=True)
class _ChunkInfo:
    pos: int
    start: int
    end: int
    counts: dict[int, int]


class BagWriter:
    """Writes one new ROS 1 bag; message records carry the time given, payloads are stored as they are."""

    def __init__(
        self,
        path: str | Path,
        compression: str = "none",
        chunk_threshold: int = CHUNK_THRESHOLD,
        max_chunk_age: float = 1.0,
    ) -> None:
        if compression != "none" and compression not in COMPRESSORS:
            raise ValueError(f"unknown compression {compression!r}")
        self.path = Path(path)
        self.compression = compression
        self.chunk_threshold = chunk_threshold
        self.max_chunk_age = max_chunk_age
        self._file: BinaryIO = self.path.open("xb", buffering=0)
        self._buf = bytearray()
        self._disk = 0  # bytes that reached the file
        self._failed: OSError | None = None
        self._closed = False
        self._connections: dict[tuple[tuple[str, str], ...], int] = {}
        self._conn_records: list[tuple[int, bytes]] = []  # (id, full connection record)
        self._infos: list[_ChunkInfo] = []
        self._chunk: _Chunk | None = None
        self.messages = 0
        self._buf += fmt.MAGIC + _file_header(0, 0, 0)
        self._out()

    # -- facts -----------------------------------------------------------------------------------
    @property
    def size(self) -> int:
        """Bytes of the file so far, including what is still buffered."""
        pending = len(self._chunk.memory) if self._chunk is not None else 0
        return self._disk + len(self._buf) + pending

    @property
    def failed(self) -> OSError | None:
        return self._failed

    @property
    def kept(self) -> int:
        """Messages the closed file indexes (fewer than `messages` only after a write failure)."""
        return sum(sum(info.counts.values()) for info in self._infos)

    # -- writing ---------------------------------------------------------------------------------
    def connection(self, header: Mapping[str, str]) -> int:
        """The id of the connection with this header (topic, type, md5sum, message_definition, ...)."""
        key = tuple(sorted(header.items()))
        conn_id = self._connections.get(key)
        if conn_id is not None:
            return conn_id
        conn_id = len(self._connections)
        self._connections[key] = conn_id
        fields = {name: value.encode() for name, value in header.items()}
        record_header = fmt.build_header(
            {"op": bytes([fmt.OP_CONNECTION]), "conn": fmt.u32(conn_id), "topic": fields["topic"]}
        )
        data = fmt.build_header(fields)[4:]  # the connection header, without its length prefix
        record = record_header + fmt.u32(len(data)) + data
        self._conn_records.append((conn_id, record))
        self._append(record)  # inside the current chunk too, as rosbag does (reindex finds it there)
        return conn_id

    def write(self, conn_id: int, time_ns: int, payload: bytes | memoryview) -> None:
        if self._failed is not None:
            raise WriteFailed(str(self._failed))
        sec, nsec = divmod(time_ns, 1_000_000_000)
        chunk = self._open_chunk()
        offset = chunk.size
        self._append(_MSG.pack(_MSG_HEADER_LEN, 4, b"op=\x02", 9, b"conn=", conn_id, 13, b"time=", sec, nsec,
                               len(payload)))  # fmt: skip
        if self.compression == "none" and len(payload) >= _DIRECT:
            self._out(payload)  # big payloads go to the file without a copy into the buffer
            chunk.size += len(payload)
        else:
            self._append(payload)
        entries = chunk.index.get(conn_id)
        if entries is None:
            entries = chunk.index[conn_id] = bytearray()
        entries += _INDEX_ENTRY.pack(sec, nsec, offset)
        chunk.counts[conn_id] = chunk.counts.get(conn_id, 0) + 1
        chunk.ends.append((offset, chunk.size, conn_id, time_ns))
        chunk.start = min(chunk.start, time_ns)
        chunk.end = max(chunk.end, time_ns)
        self.messages += 1
        if chunk.size >= self.chunk_threshold:
            self._close_chunk()
        elif len(self._buf) >= _BUFFER:
            self._out()

    def flush(self) -> None:
        """Push everything written so far to the OS (a compressed chunk only once it is old enough)."""
        if self._failed is not None:
            raise WriteFailed(str(self._failed))
        chunk = self._chunk
        if chunk is not None and chunk.memory and time.monotonic() - chunk.opened >= self.max_chunk_age:
            self._close_chunk()
        if self._buf:
            self._out()

    def close(self) -> None:
        """Close the last chunk and write the index; after a write failure, index what is on disk.

        Raises WriteFailed when even that is impossible (the file then stays unindexed: reindex it)."""
        if self._closed:
            return
        try:
            if self._failed is None:
                try:
                    if self._chunk is not None:
                        self._close_chunk()
                    self._write_index()
                    return
                except OSError:
                    pass  # kept in self._failed; index what reached the disk below
            try:
                self._recover()
            except OSError as err:
                raise WriteFailed(str(err)) from err
        finally:
            self._closed = True
            self._file.close()

    def abort(self) -> None:
        """Stop without an index (as a killed recorder would); `bag reindex` can still recover the file."""
        if not self._closed:
            self._closed = True
            self._file.close()

    # -- chunks ----------------------------------------------------------------------------------
    def _open_chunk(self) -> _Chunk:
        chunk = self._chunk
        if chunk is not None:
            return chunk
        pos = self._disk + len(self._buf)
        chunk = _Chunk(pos, pos + len(self._chunk_header(0)) + 4)
        if self.compression == "none":
            self._buf += self._chunk_header(0) + fmt.u32(0)  # sizes patched when the chunk closes
        self._chunk = chunk
        return chunk

    def _chunk_header(self, size: int) -> bytes:
        # `size` must stay the last field: _patch_sizes relies on it.
        return fmt.build_header(
            {"op": bytes([fmt.OP_CHUNK]), "compression": self.compression.encode(), "size": fmt.u32(size)}
        )

    def _append(self, data: bytes | memoryview) -> None:
        chunk = self._open_chunk()
        if self.compression == "none":
            self._buf += data
        else:
            chunk.memory += data
        chunk.size += len(data)

    def _close_chunk(self) -> None:
        chunk = self._chunk
        assert chunk is not None
        if self.compression == "none":
            self._patch_sizes(chunk, chunk.size)
        else:
            data = COMPRESSORS[self.compression](bytes(chunk.memory))
            chunk.pos = self._disk + len(self._buf)
            self._buf += self._chunk_header(chunk.size) + fmt.u32(len(data)) + data
        self._buf += _index_records(chunk.index, chunk.counts)
        self._out()  # on failure the chunk stays current, for _recover
        self._chunk = None
        self._infos.append(_ChunkInfo(chunk.pos, chunk.start, chunk.end, chunk.counts))

    def _patch_sizes(self, chunk: _Chunk, size: int) -> None:
        """Write the final `size` (uncompressed) and data length into a streamed chunk's header."""
        offset, data = chunk.data_pos - 8, _U32.pack(size) * 2
        if offset >= self._disk:
            start = offset - self._disk
            self._buf[start : start + len(data)] = data
        else:
            self._pwrite(data, offset)

    # -- index -----------------------------------------------------------------------------------
    def _write_index(self) -> None:
        self._out()
        index_pos = self._disk
        for _conn_id, record in self._conn_records:
            self._buf += record
        for info in self._infos:
            header = fmt.build_header(
                {
                    "op": bytes([fmt.OP_CHUNK_INFO]),
                    "ver": fmt.u32(1),
                    "chunk_pos": fmt.u64(info.pos),
                    "start_time": fmt.time_bytes(0 if info.start == 2**63 - 1 else info.start),
                    "end_time": fmt.time_bytes(info.end),
                    "count": fmt.u32(len(info.counts)),
                }
            )
            body = b"".join(fmt.u32(conn) + fmt.u32(n) for conn, n in info.counts.items())
            self._buf += header + fmt.u32(len(body)) + body
        self._out()
        self._pwrite(_file_header(index_pos, len(self._conn_records), len(self._infos)), len(fmt.MAGIC))

    def _recover(self) -> None:
        """After a failed write: keep the complete records on disk, cut the rest, index what is left.

        Complete messages on disk are never cut to make room for an index: when the index of the chunk
        being written does not fit, the file is left without index (complete records only) and
        WriteFailed says so; `rostool bag reindex` rebuilds the index once there is room."""
        self._buf.clear()
        chunk, self._chunk = self._chunk, None
        if chunk is not None and self.compression == "none" and chunk.data_pos <= self._disk:
            on_disk = self._disk - chunk.data_pos
            kept = [entry for entry in chunk.ends if entry[1] <= on_disk]
            if kept:
                try:
                    self._keep_records(chunk, kept)
                    return
                except OSError as err:
                    self._cut(chunk.data_pos + kept[-1][1])
                    raise WriteFailed(f"no room for the index: {err.strerror or err}") from err
        self._cut(min(chunk.pos, self._disk) if chunk is not None else self._disk)
        self._write_index()

    def _keep_records(self, chunk: _Chunk, kept: list[tuple[int, int, int, int]]) -> None:
        used = kept[-1][1]
        self._cut(chunk.data_pos + used)
        self._patch_sizes(chunk, used)
        index: dict[int, bytearray] = {}
        counts: dict[int, int] = {}
        for offset, _end, conn, stamp in kept:
            sec, nsec = divmod(stamp, 1_000_000_000)
            index.setdefault(conn, bytearray()).extend(_INDEX_ENTRY.pack(sec, nsec, offset))
            counts[conn] = counts.get(conn, 0) + 1
        self._buf += _index_records(index, counts)
        times = [stamp for _o, _e, _c, stamp in kept]
        self._infos.append(_ChunkInfo(chunk.pos, min(times), max(times), counts))
        self._write_index()

    def _cut(self, size: int) -> None:
        self._buf.clear()
        os.ftruncate(self._file.fileno(), size)
        self._disk = size

    # -- output ----------------------------------------------------------------------------------
    def _out(self, extra: bytes | memoryview | None = None) -> None:
        """Write the buffer (then `extra`) at the end of the file; `_disk` counts what got there."""
        if not self._buf and extra is None:
            return
        views = [memoryview(self._buf)]
        if extra is not None:
            views.append(memoryview(extra))
        fd = self._file.fileno()
        try:
            while views:
                written = os.pwritev(fd, views, self._disk)
                self._disk += written
                while views and written >= len(views[0]):
                    written -= len(views[0])
                    views.pop(0).release()
                if views and written:
                    views[0] = views[0][written:]
        except OSError as err:
            if self._failed is None:
                self._failed = err
            raise
        finally:
            for view in views:
                view.release()
        self._buf.clear()

    def _pwrite(self, data: bytes, offset: int) -> None:
        try:
            os.pwrite(self._file.fileno(), data, offset)
        except OSError as err:
            if self._failed is None:
                self._failed = err
            raise


def _file_header(index_pos: int, conn_count: int, chunk_count: int) -> bytes:
    record = fmt.build_header(
        {
            "op": bytes([fmt.OP_FILE_HEADER]),
            "index_pos": fmt.u64(index_pos),
            "conn_count": fmt.u32(conn_count),
            "chunk_count": fmt.u32(chunk_count),
        }
    )
    padding = fmt.FILE_HEADER_LENGTH - len(record) - 4
    return record + fmt.u32(padding) + b" " * padding


def _index_records(index: Mapping[int, bytearray], counts: Mapping[int, int]) -> bytes:
    parts = []
    for conn_id, entries in index.items():
        header = fmt.build_header(
            {
                "op": bytes([fmt.OP_INDEX_DATA]),
                "ver": fmt.u32(1),
                "conn": fmt.u32(conn_id),
                "count": fmt.u32(counts[conn_id]),
            }
        )
        parts.append(header + fmt.u32(len(entries)) + bytes(entries))
    return b"".join(parts)
