"""`bag reindex` of an .mcap file: copy every readable record into a new file whose writer adds the summary
and indexes; the complete records of a chunk the file ends in the middle of are kept too."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any, BinaryIO

from rostool.bag.bounded import inflate_prefix
from rostool.bag.failures import describe
from rostool.errors import RostoolError

MAGIC = b"\x89MCAP0\r\n"


def mcap_complete(path: Path) -> bool:
    """The file ends with the footer and closing magic (its writer finished it)."""
    size = path.stat().st_size
    if size < 2 * len(MAGIC) + 29:
        return False
    with path.open("rb") as handle:
        handle.seek(size - len(MAGIC))
        return handle.read() == MAGIC


def rebuild_mcap(path: Path, tmp: Path) -> tuple[int, int, bool]:
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
