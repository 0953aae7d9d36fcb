"""`bag reindex`: make a bag whose writer died readable again (rosbags has no reindexing; written here).

ROS 1: walk the records from the start, keep every chunk and, from the last, half-written chunk, every
message record that is complete on disk (`rosbag reindex` drops that chunk whole); then write fresh index
records, the connection and chunk-info records and a bag header pointing at them. The original is kept as
`NAME.orig.bag`, as `rosbag reindex` does.
mcap: copy every readable record into a new file whose writer adds the summary and indexes (`NAME.orig.mcap`
keeps the original).
rosbag2 directory (also `NAME.mcap.active/` or `NAME.db3.active/` left by a killed `bag record`), as
`ros2 bag reindex` does: repair each cut-short .mcap as above, roll back a .db3's unfinished transaction
(rosbags opens sqlite files immutable, ignoring a hot journal), then write metadata.yaml from what the
storage files hold. The original directory's files are kept in `DIR.orig/` (hard links where unchanged).
"""

from __future__ import annotations

import errno
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

from rostool.bag import ros1_format as fmt
from rostool.bag.bounded import inflate_prefix
from rostool.bag.open import describe, detect
from rostool.errors import RostoolError


@dataclass
class ReindexResult:
    path: Path
    backup: Path
    messages: int
    chunks: int
    partial: bool  # messages were recovered from a half-written last chunk


def backup_path(path: Path) -> Path:
    suffix = path.suffix if path.suffix in (".bag", ".mcap") else ""
    return path.with_name(f"{path.name.removesuffix(suffix)}.orig{suffix or '.bag'}")


def reindex(given: str | Path) -> ReindexResult:
    if Path(given).is_dir() or Path(given).name == "metadata.yaml":
        from rostool.bag.reindex_rosbag2 import reindex_rosbag2

        return reindex_rosbag2(Path(given))
    bag = detect(given)
    if bag.kind not in ("bag", "mcap") or len(bag.files) != 1 or bag.path.is_dir():
        raise RostoolError(f"{bag.path}: reindex works on a ROS 1 .bag or a single .mcap file")
    path = bag.path
    backup = backup_path(path)
    if backup.exists():
        raise RostoolError(f"{backup} exists (from an earlier reindex?); move it away first")
    tmp = path.with_name(f".{path.name}.reindex-{os.getpid()}")
    try:
        if bag.kind == "bag":
            messages, chunks, partial = _reindex_ros1(path, tmp)
        else:
            messages, chunks, partial = reindex_mcap(path, tmp)
        os.replace(path, backup)
        os.replace(tmp, path)
    except BaseException as err:
        tmp.unlink(missing_ok=True)
        if isinstance(err, OSError) and err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
            raise RostoolError(
                f"{path}: no room for the rebuilt copy ({err.strerror}); the file is untouched: free some "
                "space and retry"
            ) from err
        raise
    return ReindexResult(path, backup, messages, chunks, partial)


# -- ROS 1 ---------------------------------------------------------------------------------------
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


def _reindex_ros1(path: Path, tmp: Path) -> tuple[int, int, bool]:
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


# -- mcap ----------------------------------------------------------------------------------------
def mcap_complete(path: Path) -> bool:
    """The file ends with the footer and closing magic (its writer finished it)."""
    from rostool.bag.open import MCAP_MAGIC

    size = path.stat().st_size
    if size < 2 * len(MCAP_MAGIC) + 29:
        return False
    with path.open("rb") as handle:
        handle.seek(size - len(MCAP_MAGIC))
        return handle.read() == MCAP_MAGIC


def reindex_mcap(path: Path, tmp: Path) -> tuple[int, int, bool]:
    from mcap.records import Header
    from mcap.stream_reader import StreamReader
    from mcap.writer import CompressionType, Writer

    messages = 0
    truncated = False
    with path.open("rb") as source, tmp.open("xb") as out:
        writer: Writer | None = None
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        records = iter(StreamReader(source).records)
        while True:
            try:
                record = next(records)
            except StopIteration:
                break
            except (
                Exception
            ):  # whatever a cut-short or damaged tail makes the parser raise: keep what came before
                truncated = True
                break
            if isinstance(record, Header):
                if writer is None:
                    writer = Writer(out, compression=CompressionType.ZSTD)
                    writer.start(record.profile, record.library or "rostool")
                continue
            if writer is None:
                raise RostoolError(f"{path}: no mcap header record")
            try:
                messages += _copy_record(record, writer, schemas, channels)
            except OSError:
                raise
            except Exception as err:  # values the parser accepted but the writer cannot write back
                raise RostoolError(f"{path}: cannot rebuild it: {describe(err)}") from err
        if writer is None:
            raise RostoolError(f"{path}: no readable mcap header")
        from_cut = 0
        if truncated:  # the stream reader skips a chunk the file ends in: take its complete records
            for record in _cut_chunk_records(source, path.stat().st_size):
                from_cut += _copy_record(record, writer, schemas, channels)
        writer.finish()
    return messages + from_cut, 0, from_cut > 0


_TOP = struct.Struct("<BQ")  # an mcap record's opcode and length
_CHUNK_START = struct.Struct("<QQQI")  # message start/end time, uncompressed size, crc
_OP_CHUNK = 0x06


def _cut_chunk_records(handle: BinaryIO, size: int) -> list[Any]:
    """The complete records inside the chunk an mcap file ends in the middle of (a recorder killed while
    writing it), decompressed no further than the size the chunk declares; [] when the file does not end
    inside a chunk."""
    from io import BytesIO

    from mcap.stream_reader import StreamReader

    pos = 8  # after the magic
    while True:
        handle.seek(pos)
        head = handle.read(_TOP.size)
        if len(head) < _TOP.size:
            return []
        opcode, length = _TOP.unpack(head)
        if pos + _TOP.size + length <= size:
            pos += _TOP.size + length
            continue
        if opcode != _OP_CHUNK:
            return []
        body = handle.read(size - pos - _TOP.size)
        break
    try:
        _start, _end, declared, _crc = _CHUNK_START.unpack_from(body, 0)
        (name_length,) = struct.unpack_from("<I", body, _CHUNK_START.size)
        at = _CHUNK_START.size + 4
        compression = body[at : at + name_length].decode("ascii")
        data = body[at + name_length + 8 :]
    except (struct.error, UnicodeDecodeError):
        return []
    if compression in ("zstd", "lz4"):
        raw = inflate_prefix(compression, data, declared)
    elif compression == "":
        raw = data[:declared]
    else:
        return []
    records: list[Any] = []
    try:
        for record in StreamReader(BytesIO(raw), skip_magic=True).records:
            records.append(record)
    except Exception:  # the last, incomplete record (or damage): what came before is true
        pass
    return records


def _copy_record(record: object, writer: Any, schemas: dict[int, int], channels: dict[int, int]) -> int:
    """Write one mcap record into the new file; 1 for a message, else 0."""
    from mcap.records import Attachment, Channel, Message, Metadata, Schema

    if isinstance(record, Schema) and record.id not in schemas:
        schemas[record.id] = writer.register_schema(record.name, record.encoding, record.data)
    elif isinstance(record, Channel) and record.id not in channels:
        schema = schemas.get(record.schema_id, 0)
        channels[record.id] = writer.register_channel(
            record.topic, record.message_encoding, schema, record.metadata
        )
    elif isinstance(record, Message) and record.channel_id in channels:
        writer.add_message(
            channels[record.channel_id], record.log_time, record.data, record.publish_time, record.sequence
        )
        return 1
    elif isinstance(record, Attachment):
        writer.add_attachment(
            record.create_time, record.log_time, record.name, record.media_type, record.data
        )
    elif isinstance(record, Metadata):
        writer.add_metadata(record.name, record.metadata)
    return 0
