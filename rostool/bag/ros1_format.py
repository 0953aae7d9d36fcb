"""ROS 1 bag v2.0 records: just enough to read the index quickly and to rebuild it.

rosbags' rosbag1.Reader reads every chunk's index records on open (fine for reading messages, slow for
`info` on a multi-GB bag) and cannot read an unindexed bag at all; `rosbag info` needs only the connection
and chunk-info records plus each chunk's header, and `reindex` needs to walk the raw records. Both are
written here with struct only, so `bag info` on a .bag imports nothing heavy.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass, field
from typing import BinaryIO

from rostool.errors import RostoolError

MAGIC = b"#ROSBAG V2.0\n"
OP_MSG_DATA = 0x02
OP_FILE_HEADER = 0x03
OP_INDEX_DATA = 0x04
OP_CHUNK = 0x05
OP_CHUNK_INFO = 0x06
OP_CONNECTION = 0x07
FILE_HEADER_LENGTH = 4096

_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
_TIME = struct.Struct("<II")


class FormatError(RostoolError):
    pass


def parse_header(data: bytes | memoryview) -> dict[str, bytes]:
    """The `name=value` fields of a record header."""
    fields: dict[str, bytes] = {}
    pos, end = 0, len(data)
    while pos < end:
        if pos + 4 > end:
            raise FormatError("record header field is cut off")
        (size,) = _U32.unpack_from(data, pos)
        pos += 4
        if pos + size > end:
            raise FormatError("record header field is longer than its header")
        raw = bytes(data[pos : pos + size])
        name, sep, value = raw.partition(b"=")
        if not sep:
            raise FormatError("record header field without '='")
        fields[name.decode(errors="replace")] = value
        pos += size
    return fields


def build_header(fields: dict[str, bytes]) -> bytes:
    body = b"".join(
        _U32.pack(len(name) + 1 + len(value)) + name.encode() + b"=" + value for name, value in fields.items()
    )
    return _U32.pack(len(body)) + body


def u32(value: int) -> bytes:
    return _U32.pack(value)


def u64(value: int) -> bytes:
    return _U64.pack(value)


def time_bytes(ns: int) -> bytes:
    return _TIME.pack(ns // 1_000_000_000, ns % 1_000_000_000)


def get_u32(fields: dict[str, bytes], name: str) -> int:
    try:
        return int(_U32.unpack(fields[name])[0])
    except (KeyError, struct.error) as err:
        raise FormatError(f"record field {name!r} missing or invalid") from err


def get_u64(fields: dict[str, bytes], name: str) -> int:
    try:
        return int(_U64.unpack(fields[name])[0])
    except (KeyError, struct.error) as err:
        raise FormatError(f"record field {name!r} missing or invalid") from err


def get_time(fields: dict[str, bytes], name: str) -> int:
    try:
        sec, nsec = _TIME.unpack(fields[name])
    except (KeyError, struct.error) as err:
        raise FormatError(f"record field {name!r} missing or invalid") from err
    return int(sec) * 1_000_000_000 + int(nsec)


def get_op(fields: dict[str, bytes]) -> int:
    op = fields.get("op")
    if not op or len(op) != 1:
        raise FormatError("record without op code")
    return op[0]


def _check_left(handle: BinaryIO, length: int) -> None:
    """A length past the end of the file is damage: say so before allocating gigabytes for it."""
    try:
        left = os.fstat(handle.fileno()).st_size - handle.tell()
    except (OSError, AttributeError, ValueError):  # not a real file: the short read says it
        return
    if length > left:
        raise FormatError(f"a record claims {length} bytes where the file has {max(left, 0)} left")


def read_record(handle: BinaryIO, with_data: bool = True) -> tuple[dict[str, bytes], bytes, int]:
    """(header fields, data, data length) of the record at the current position."""
    raw = handle.read(4)
    if len(raw) < 4:
        raise FormatError("unexpected end of file")
    (length,) = _U32.unpack(raw)
    _check_left(handle, length)
    header = handle.read(length)
    if len(header) < length:
        raise FormatError("unexpected end of file in a record header")
    raw = handle.read(4)
    if len(raw) < 4:
        raise FormatError("unexpected end of file")
    (data_length,) = _U32.unpack(raw)
    if with_data:
        _check_left(handle, data_length)
        data = handle.read(data_length)
        if len(data) < data_length:
            raise FormatError("unexpected end of file in record data")
    else:
        data = b""
        handle.seek(data_length, 1)
    return parse_header(header), data, data_length


@dataclass
class Connection:
    id: int
    topic: str
    datatype: str
    md5sum: str
    fields: dict[str, bytes]  # the connection header: type, md5sum, message_definition, callerid...


@dataclass
class ChunkInfo:
    pos: int
    start_ns: int
    end_ns: int
    counts: dict[int, int]


@dataclass
class ChunkHeader:
    compression: str
    uncompressed_size: int
    compressed_size: int
    data_pos: int


@dataclass
class Index:
    """The index section of a ROS 1 bag, as `rosbag info` reads it."""

    connections: dict[int, Connection] = field(default_factory=dict)
    chunks: list[ChunkInfo] = field(default_factory=list)
    chunk_headers: list[ChunkHeader] = field(default_factory=list)


def read_file_header(handle: BinaryIO) -> dict[str, bytes]:
    handle.seek(0)
    magic = handle.read(len(MAGIC))
    if magic != MAGIC:
        raise FormatError("not a ROS 1 bag v2.0 (bad magic)")
    fields, _data, _length = read_record(handle, with_data=False)
    if get_op(fields) != OP_FILE_HEADER:
        raise FormatError("bag header record missing")
    return fields


def read_connection(fields: dict[str, bytes], data: bytes) -> Connection:
    conn = parse_header(data)
    return Connection(
        id=get_u32(fields, "conn"),
        topic=fields.get("topic", b"").decode(errors="replace"),
        datatype=conn.get("type", b"").decode(errors="replace"),
        md5sum=conn.get("md5sum", b"").decode(errors="replace"),
        fields=conn,
    )


def read_index(handle: BinaryIO, with_chunk_headers: bool = True) -> Index:
    """Connections, chunk infos and (optionally) chunk headers; raises FormatError if unindexed."""
    header = read_file_header(handle)
    index_pos = get_u64(header, "index_pos")
    conn_count = get_u32(header, "conn_count")
    chunk_count = get_u32(header, "chunk_count")
    if header.get("encryptor"):
        raise FormatError(
            f"encrypted bags ({header['encryptor'].decode(errors='replace')}) are not supported"
        )
    if index_pos == 0:
        raise FormatError("bag is not indexed (its recorder was killed?); run `rostool bag reindex`")
    index = Index()
    handle.seek(index_pos)
    for _ in range(conn_count):
        fields, data, _length = read_record(handle)
        if get_op(fields) != OP_CONNECTION:
            raise FormatError("bag index is damaged: expected a connection record")
        conn = read_connection(fields, data)
        index.connections[conn.id] = conn
    for _ in range(chunk_count):
        fields, data, _length = read_record(handle)
        if get_op(fields) != OP_CHUNK_INFO:
            raise FormatError("bag index is damaged: expected a chunk info record")
        count = get_u32(fields, "count")
        counts = {}
        for i in range(count):
            conn_id, n = struct.unpack_from("<II", data, i * 8)
            counts[conn_id] = n
        index.chunks.append(
            ChunkInfo(
                get_u64(fields, "chunk_pos"),
                get_time(fields, "start_time"),
                get_time(fields, "end_time"),
                counts,
            )
        )
    if with_chunk_headers:
        for chunk in index.chunks:
            handle.seek(chunk.pos)
            fields, _data, length = read_record(handle, with_data=False)
            if get_op(fields) != OP_CHUNK:
                raise FormatError(f"bag index is damaged: no chunk at offset {chunk.pos}")
            index.chunk_headers.append(
                ChunkHeader(
                    fields.get("compression", b"none").decode(), get_u32(fields, "size"), length, chunk.pos
                )
            )
    return index


def read_index_times(handle: BinaryIO, index: Index) -> dict[int, list[int]]:
    """Receive times (ns) of every message by connection, from the index records after each chunk."""
    times: dict[int, list[int]] = {conn: [] for conn in index.connections}
    for chunk in index.chunks:
        handle.seek(chunk.pos)
        read_record(handle, with_data=False)
        for _ in range(len(chunk.counts)):
            fields, data, _length = read_record(handle)
            if get_op(fields) != OP_INDEX_DATA:
                break
            entries = times.setdefault(get_u32(fields, "conn"), [])
            for pos in range(0, len(data) - 11, 12):
                sec, nsec = _TIME.unpack_from(data, pos)
                entries.append(sec * 1_000_000_000 + nsec)
    for entries in times.values():
        entries.sort()
    return times
