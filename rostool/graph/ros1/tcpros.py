"""TCPROS framing: connection headers and length-prefixed messages."""

from __future__ import annotations

import socket
import struct
import time
from typing import Protocol

_LENGTH = struct.Struct("<I")
MAX_FRAME = 1 << 30
# A connection header (fields and one message definition) is a few kilobytes; roscpp refuses absurd
# lengths too. Past this the peer is broken or hostile: close at once, allocate nothing.
MAX_HEADER = 4 << 20
HANDSHAKE_TIMEOUT = 10.0  # the whole header, however slowly it trickles in
_PIECE = 1 << 20  # big frames are read piece by piece: memory grows with bytes received, not promised


class Readable(Protocol):
    def read(self, size: int = -1, /) -> bytes | None: ...


class ConnectionClosed(Exception):
    """The peer closed the connection (or sent something we cannot frame)."""


def encode_header(fields: dict[str, str]) -> bytes:
    body = b"".join(
        _LENGTH.pack(len(item)) + item for item in (f"{k}={v}".encode() for k, v in fields.items())
    )
    return _LENGTH.pack(len(body)) + body


def decode_header(body: bytes) -> dict[str, str]:
    fields: dict[str, str] = {}
    offset = 0
    while offset + 4 <= len(body):
        (size,) = _LENGTH.unpack_from(body, offset)
        offset += 4
        item = body[offset : offset + size].decode("utf-8", errors="replace")
        offset += size
        key, _, value = item.partition("=")
        fields[key] = value
    return fields


def read_exact(stream: Readable, size: int) -> bytes:
    if size > _PIECE:
        parts, left = [], size
        while left:
            part = read_exact(stream, min(left, _PIECE))
            parts.append(part)
            left -= len(part)
        return b"".join(parts)
    data = stream.read(size)
    if data is None or len(data) < size:
        raise ConnectionClosed
    return data


def read_frame(stream: Readable) -> bytes:
    (size,) = _LENGTH.unpack(read_exact(stream, 4))
    if size > MAX_FRAME:
        raise ConnectionClosed
    return read_exact(stream, size) if size else b""


def read_header(stream: Readable) -> dict[str, str]:
    (size,) = _LENGTH.unpack(read_exact(stream, 4))
    if size > MAX_HEADER:
        raise ConnectionClosed
    return decode_header(read_exact(stream, size) if size else b"")


def read_handshake(sock: socket.socket, timeout: float = HANDSHAKE_TIMEOUT) -> dict[str, str]:
    """A connection header read straight from the socket within `timeout` seconds overall (a peer that
    trickles it byte by byte is cut off too); raises ConnectionClosed (or TimeoutError)."""
    deadline = time.monotonic() + timeout

    def exact(size: int) -> bytes:
        data = bytearray()
        while len(data) < size:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError("the connection header took too long")
            sock.settimeout(remaining)
            part = sock.recv(min(size - len(data), _PIECE))
            if not part:
                raise ConnectionClosed
            data += part
        return bytes(data)

    (size,) = _LENGTH.unpack(exact(4))
    if size > MAX_HEADER:
        raise ConnectionClosed
    return decode_header(exact(size) if size else b"")


def frame(payload: bytes | memoryview) -> bytes:
    return _LENGTH.pack(len(payload)) + bytes(payload)


def connect(host: str, port: int, timeout: float = 5.0) -> socket.socket:
    sock = socket.create_connection((host, port), timeout=timeout)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    sock.settimeout(None)
    return sock
