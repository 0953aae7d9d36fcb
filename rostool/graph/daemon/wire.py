"""Messages on the daemon's socket: a 4-byte big-endian length, then that many bytes of UTF-8 JSON.

Requests: {"op": "query", "build": B, "method": M, "args": [...], "own": GUID (hex, optional: the client's
participant)}, {"op": "status"}, {"op": "stop"}.
Answers: {"ok": value}, {"error": "one line"} (a RostoolError the backend raised) or {"build": B} when
the daemon is of another build than the client (it then stops, to be replaced).
"""

from __future__ import annotations

import json
import socket
import struct
from typing import Any

MAX_MESSAGE = 32 * 1024 * 1024
_HEADER = struct.Struct(">I")


class WireError(Exception):
    """The other side broke the framing, sent too much, closed early or did not answer in time."""


def send(sock: socket.socket, message: Any) -> None:
    body = json.dumps(message, separators=(",", ":")).encode()
    if len(body) > MAX_MESSAGE:
        raise WireError(f"message of {len(body)} bytes is over the {MAX_MESSAGE}-byte limit")
    try:
        sock.sendall(_HEADER.pack(len(body)) + body)
    except OSError as err:  # socket.timeout included
        raise WireError(f"cannot send: {err}") from None


def receive(sock: socket.socket) -> Any:
    (size,) = _HEADER.unpack(_exactly(sock, _HEADER.size))
    if size > MAX_MESSAGE:
        raise WireError(f"message of {size} bytes is over the {MAX_MESSAGE}-byte limit")
    try:
        return json.loads(_exactly(sock, size))
    except ValueError as err:
        raise WireError(f"not JSON: {err}") from None


def _exactly(sock: socket.socket, size: int) -> bytes:
    chunks = bytearray()
    while len(chunks) < size:
        try:
            chunk = sock.recv(min(size - len(chunks), 1 << 20))
        except OSError as err:  # socket.timeout included
            raise WireError(f"cannot receive: {err or 'timed out'}") from None
        if not chunk:
            raise WireError("closed before the message ended")
        chunks.extend(chunk)
    return bytes(chunks)
