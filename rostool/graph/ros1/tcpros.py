"""TCPROS framing: connection headers and length-prefixed messages."""

from __future__ import annotations

import socket
import struct
from typing import Protocol

_LENGTH = struct.Struct("<I")
MAX_FRAME = 1 << 30


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
    return decode_header(read_frame(stream))


def frame(payload: bytes | memoryview) -> bytes:
    return _LENGTH.pack(len(payload)) + bytes(payload)


def connect(host: str, port: int, timeout: float = 5.0) -> socket.socket:
    sock = socket.create_connection((host, port), timeout=timeout)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    sock.settimeout(None)
    return sock
