"""Chunk decompression bounded by the size the chunk declares: a decompression bomb (a chunk whose header
says a few kilobytes and whose data inflates to gigabytes) stops at that size and fails in one line.

rosbags (ROS 1 .bag chunks: bz2/lz4; rosbag2 .mcap chunks: zstd/lz4) and the mcap library inflate a chunk
whole, trusting the compressed stream; `install()` (called when a bag is opened) gives them `inflate`.
"""

from __future__ import annotations

import bz2
import functools
from collections.abc import Callable
from io import BytesIO
from typing import Any

from rostool.errors import RostoolError

MARGIN = 64  # bytes past the declared size read to tell "more than declared" from "exactly declared"
_PIECE = 1 << 20


class Inflates(RostoolError):
    """A chunk does not decompress to the size its header declares."""


def inflate(kind: str, data: bytes | memoryview, declared: int, partial: bool = False) -> bytes:
    """At most `declared` bytes of the decompressed `data`; more (or, unless `partial`, fewer or a broken
    stream) raises Inflates. `partial`: the stream may be cut short; return what it gives."""
    out, error = _DECODERS[kind](bytes(data), declared + MARGIN)
    if len(out) > declared:
        raise Inflates(
            f"a {kind} chunk inflates past the {declared} bytes its header declares (a damaged or hostile "
            f"bag); stopped there"
        )
    if partial:
        return out
    if error is not None:
        reason = " ".join(str(error).split()) or type(error).__name__
        raise Inflates(f"a {kind} chunk does not decompress ({reason}); try `rostool bag reindex`") from error
    if len(out) < declared:
        raise Inflates(f"a {kind} chunk holds {len(out)} bytes where its header says {declared}")
    return out


def inflate_prefix(kind: str, data: bytes | memoryview, declared: int) -> bytes:
    """For recovery: what a (possibly cut-short, possibly hostile) chunk gives, at most `declared` bytes."""
    return _DECODERS[kind](bytes(data), declared)[0]


Decoded = tuple[bytes, Exception | None]  # what came out before the end (or the error)


def _pieces(step: Callable[[int], bytes], limit: int, errors: tuple[type[Exception], ...]) -> Decoded:
    parts, got = [], 0
    try:
        while got < limit:
            part = step(min(_PIECE, limit - got))
            if not part:
                break
            parts.append(bytes(part))
            got += len(part)
    except errors as err:
        return b"".join(parts), err
    return b"".join(parts), None


def _bz2(data: bytes, limit: int) -> Decoded:
    decoder = bz2.BZ2Decompressor()
    pending = [data]

    def step(size: int) -> bytes:
        if decoder.eof:
            return b""
        return decoder.decompress(pending.pop() if pending else b"", max_length=size)

    return _pieces(step, limit, (OSError, EOFError, ValueError))


def _lz4(data: bytes, limit: int) -> Decoded:
    import lz4.frame

    decoder = lz4.frame.LZ4FrameDecompressor()
    pending = [data]

    def step(size: int) -> bytes:
        if decoder.eof:
            return b""
        return bytes(decoder.decompress(pending.pop() if pending else b"", max_length=size))

    return _pieces(step, limit, (RuntimeError, EOFError))


def _zstd(data: bytes, limit: int) -> Decoded:
    import zstandard

    with zstandard.ZstdDecompressor().stream_reader(BytesIO(data), read_across_frames=True) as reader:
        return _pieces(reader.read, limit, (zstandard.ZstdError,))


_DECODERS: dict[str, Callable[[bytes, int], Decoded]] = {"bz2": _bz2, "lz4": _lz4, "zstd": _zstd}


# -- the libraries -------------------------------------------------------------------------------
@functools.cache
def install() -> None:
    """Route rosbags' and the mcap library's chunk decompression through `inflate`."""
    _install_rosbag1()
    _install_rosbags_mcap()
    _install_mcap()


def _install_rosbag1() -> None:
    import os

    from rosbags.rosbag1 import reader as rosbag1

    def read_chunk(self: Any) -> Any:  # rosbags' Reader.read_chunk, with the declared size kept
        header = rosbag1.Header.read(self.bio, rosbag1.RecordType.CHUNK)
        compression = header.get_string("compression")
        declared = header.get_uint32("size")
        datasize = rosbag1.read_uint32(self.bio)
        datapos = self.bio.tell()
        self.bio.seek(datasize, os.SEEK_CUR)
        if compression == "none":
            decompressor: Callable[[bytes], bytes] = bytes
        elif compression in _DECODERS:
            decompressor = functools.partial(_inflate_in, str(self.path), compression, declared)
        else:
            raise rosbag1.ReaderError(f"Compression {compression!r} is not supported.")
        return rosbag1.Chunk(datasize, datapos, decompressor)

    rosbag1.Reader.read_chunk = read_chunk


def _inflate_in(path: str, kind: str, declared: int, data: bytes) -> bytes:
    try:
        return inflate(kind, data, declared)
    except Inflates as err:
        raise Inflates(f"{path}: {err}") from err


def _install_rosbags_mcap() -> None:
    from rosbags.rosbag2 import storage_mcap

    for kind in ("lz4", "zstd"):
        storage_mcap.DECOMPRESSORS[kind] = functools.partial(_by_size, kind)


def _by_size(kind: str, data: bytes, size: int) -> bytes:
    return inflate(kind, data, size)


def _install_mcap() -> None:
    from mcap import stream_reader
    from mcap.data_stream import ReadDataStream

    original = stream_reader.get_chunk_data_stream

    def get_chunk_data_stream(chunk: Any, validate_crc: bool = False) -> tuple[Any, int]:
        if chunk.compression not in ("zstd", "lz4"):
            return original(chunk, validate_crc)
        data = inflate(chunk.compression, chunk.data, chunk.uncompressed_size)
        if validate_crc and chunk.uncompressed_crc:
            import zlib

            if zlib.crc32(data) != chunk.uncompressed_crc:
                raise Inflates("a chunk's checksum does not match its data")
        return ReadDataStream(BytesIO(data)), len(data)

    stream_reader.get_chunk_data_stream = get_chunk_data_stream
