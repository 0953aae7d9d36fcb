"""`bag reindex` of a ROS 1 bag: walk the records from the start, keep every chunk and, from the last,
half-written chunk, every message record that is complete on disk (`rosbag reindex` drops that chunk whole);
then write fresh index records, the connection and chunk-info records and a bag header pointing at them."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

from rostool.bag import ros1_format as fmt
from rostool.bag.bounded import inflate_prefix
from rostool.errors import RostoolError


@dataclass
class _Chunk:
    header: dict[str, bytes]  # the chunk record header (compression, size)
    data: bytes  # stored (possibly compressed) chunk data
    entries: dict[int, list[tuple[int, int]]] = field(default_factory=dict)  # conn -> [(time, offset)]


def _inflate(compression: str, data: bytes, declared: int) -> bytes:
    """The chunk's records, at most the size its header declares (a cut-short stream gives its prefix)."""
    if compression == "none":
        return data
    if compression not in ("bz2", "lz4"):
        raise RostoolError(f"chunk compression {compression!r} is not supported")
    return inflate_prefix(compression, data, declared)


def _scan_chunk(raw: bytes, connections: dict[int, tuple[dict[str, bytes], bytes]]) -> tuple[int, _Entries]:
    """Complete records of uncompressed chunk data: (bytes used, index entries by connection)."""
    entries: _Entries = {}
    pos, end = 0, len(raw)
    while pos + 8 <= end:
        (header_len,) = fmt._U32.unpack_from(raw, pos)
        data_pos = pos + 4 + header_len + 4
        if data_pos > end:
            break
        (data_len,) = fmt._U32.unpack_from(raw, pos + 4 + header_len)
        if data_pos + data_len > end:
            break
        try:
            fields = fmt.parse_header(raw[pos + 4 : pos + 4 + header_len])
            op = fmt.get_op(fields)
            if op == fmt.OP_CONNECTION:
                conn_id = fmt.get_u32(fields, "conn")
                connections.setdefault(conn_id, (fields, raw[data_pos : data_pos + data_len]))
            elif op == fmt.OP_MSG_DATA:
                conn_id = fmt.get_u32(fields, "conn")
                entries.setdefault(conn_id, []).append((fmt.get_time(fields, "time"), pos))
        except fmt.FormatError:
            break
        pos = data_pos + data_len
    return pos, entries


_Entries = dict[int, list[tuple[int, int]]]


def rebuild_ros1(path: Path, tmp: Path) -> tuple[int, int, bool]:
    connections: dict[int, tuple[dict[str, bytes], bytes]] = {}
    chunks: list[_Chunk] = []
    partial = False
    size = path.stat().st_size
    with path.open("rb") as handle:
        try:
            fmt.read_file_header(handle)
        except fmt.FormatError as err:
            raise RostoolError(f"{path}: {err}") from err
        while handle.tell() < size:
            record = _read_header_only(handle, size)
            if record is None:
                break
            fields, data_len = record
            try:
                op = fmt.get_op(fields)
            except fmt.FormatError:
                break
            if op == fmt.OP_CHUNK and data_len == 0:
                data_len = size - handle.tell()  # a recorder killed mid-chunk leaves the size at 0
                data = handle.read(data_len)
                complete = False
            else:  # never more than the file holds: a damaged length may claim gigabytes
                data = handle.read(min(data_len, size - handle.tell()))
                complete = len(data) == data_len
            if op == fmt.OP_CHUNK:
                chunk = _recover_chunk(fields, data, complete, connections)
                if chunk is not None:
                    chunks.append(chunk)
                if not complete:
                    partial = chunk is not None
                    break
            elif not complete:
                break
            elif op == fmt.OP_CONNECTION:
                connections.setdefault(fmt.get_u32(fields, "conn"), (fields, data))
            # index data and chunk info records are rebuilt below
    _write_ros1(tmp, connections, chunks)
    return sum(len(e) for c in chunks for e in c.entries.values()), len(chunks), partial


def _read_header_only(handle: BinaryIO, size: int) -> tuple[dict[str, bytes], int] | None:
    raw = handle.read(4)
    if len(raw) < 4:
        return None
    (length,) = fmt._U32.unpack(raw)
    if length > size:
        return None
    header = handle.read(length)
    raw = handle.read(4)
    if len(header) < length or len(raw) < 4:
        return None
    try:
        return fmt.parse_header(header), fmt._U32.unpack(raw)[0]
    except fmt.FormatError:
        return None


def _recover_chunk(
    fields: dict[str, bytes],
    data: bytes,
    complete: bool,
    connections: dict[int, tuple[dict[str, bytes], bytes]],
) -> _Chunk | None:
    compression = fields.get("compression", b"none").decode(errors="replace")
    size = fields.get("size", b"")
    declared = int.from_bytes(size, "little") if len(size) == 4 else len(data) * 8
    raw = _inflate(compression, data, declared)
    used, entries = _scan_chunk(raw, connections)
    if complete and compression != "none" and used == len(raw):
        return _Chunk(fields, data, entries)  # keep the compressed bytes as they are
    if used == 0:
        return None
    # A half-written chunk (or its uncompressed prefix): store the complete records uncompressed.
    kept = raw[:used]
    header = {"op": bytes([fmt.OP_CHUNK]), "compression": b"none", "size": fmt.u32(len(kept))}
    return _Chunk(header, kept, entries)


def _write_ros1(
    tmp: Path, connections: dict[int, tuple[dict[str, bytes], bytes]], chunks: list[_Chunk]
) -> None:
    with tmp.open("xb") as out:
        out.write(fmt.MAGIC)
        out.write(b"\0" * fmt.FILE_HEADER_LENGTH)  # patched at the end
        infos = []
        for chunk in chunks:
            pos = out.tell()
            out.write(fmt.build_header(chunk.header))
            out.write(fmt.u32(len(chunk.data)))
            out.write(chunk.data)
            for conn_id, items in chunk.entries.items():
                header = {
                    "op": bytes([fmt.OP_INDEX_DATA]),
                    "ver": fmt.u32(1),
                    "conn": fmt.u32(conn_id),
                    "count": fmt.u32(len(items)),
                }
                out.write(fmt.build_header(header))
                out.write(fmt.u32(12 * len(items)))
                out.write(b"".join(fmt.time_bytes(t) + fmt.u32(offset) for t, offset in items))
            times = [t for items in chunk.entries.values() for t, _ in items]
            infos.append((pos, min(times, default=0), max(times, default=0), chunk.entries))
        index_pos = out.tell()
        used = sorted({conn for chunk in chunks for conn in chunk.entries} | set(connections))
        missing = [conn for conn in used if conn not in connections]
        if missing:
            raise RostoolError(f"no connection record for connection {missing[0]}: cannot rebuild this bag")
        for conn_id in used:
            fields, data = connections[conn_id]
            out.write(fmt.build_header(fields))
            out.write(fmt.u32(len(data)))
            out.write(data)
        for pos, start, end, entries in infos:
            header = {
                "op": bytes([fmt.OP_CHUNK_INFO]),
                "ver": fmt.u32(1),
                "chunk_pos": fmt.u64(pos),
                "start_time": fmt.time_bytes(start),
                "end_time": fmt.time_bytes(end),
                "count": fmt.u32(len(entries)),
            }
            out.write(fmt.build_header(header))
            out.write(fmt.u32(8 * len(entries)))
            out.write(b"".join(fmt.u32(conn) + fmt.u32(len(items)) for conn, items in entries.items()))
        file_header = {
            "op": bytes([fmt.OP_FILE_HEADER]),
            "index_pos": fmt.u64(index_pos),
            "conn_count": fmt.u32(len(used)),
            "chunk_count": fmt.u32(len(chunks)),
        }
        record = fmt.build_header(file_header)
        padding = fmt.FILE_HEADER_LENGTH - len(record) - 4
        out.seek(len(fmt.MAGIC))
        out.write(record + fmt.u32(padding) + b" " * padding)
