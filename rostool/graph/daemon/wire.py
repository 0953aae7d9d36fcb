"""Messages on the daemon's socket: a 4-byte big-endian length, then that many bytes of UTF-8 JSON.

Requests: {"op": "query", "build": B, "method": M, "args": [...], "own": GUID (hex, optional: the client's
participant)}, {"op": "status"}, {"op": "stop"}.
Answers: {"ok": value}, {"error": "one line"} (a RostoolError the backend raised) or {"build": B} when
the daemon is of another build than the client (it then stops, to be replaced).

A relay: {"op": "subscribe", "build": B, "topic": T, "qos": {...}} (the verb's --qos-* request) is answered
{"ok": ...} (or as a query is refused, or {"direct": why} when the daemon cannot relay it), then the daemon
streams binary frames until the client closes: a header (payload length, kind, receive time in ns) and the
payload: MESSAGE (CDR bytes), TYPE (JSON: the type's name and .msg definition, or rosbags' field definitions
where rosbags writes no .msg text (a service's event type), before its first message),
WARNING and ERROR (one line of text), DIRECT (one line: the daemon cannot serve this subscription, which
the client then makes itself), READY (once: b"1" when the daemon's reader has matched every publisher it
knew when it was made, b"0" when it knew none or one never matched in time: `bag record` starts its
--duration clock on it).

A goal (goal_server.py): {"op": "goal", "build": B, "action": A, "type": T or null, "goal": the goal's value,
"timeout": S or null}, answered as a subscription is, then (once the client sent b"g") frames: TYPE as
above, GOAL (JSON: one call of the goal's watcher, its messages as {"type", "cdr": base64}), and last
OUTCOME (JSON: the goal's outcome, or {"interrupted": true} after a cancel the client asked for with b"c"
or its end of the connection) or ERROR (the one line the goal's run failed with).
"""

from __future__ import annotations

import json
import socket
import struct
from typing import Any, BinaryIO

MAX_MESSAGE = 32 * 1024 * 1024
_HEADER = struct.Struct(">I")
MAX_SAMPLE = 512 * 1024 * 1024  # a relayed message's bytes (a DDS sample is at most 4 GiB)
_FRAME = struct.Struct(">IcQ")
MESSAGE, TYPE, WARNING, ERROR, DIRECT, READY = b"m", b"t", b"w", b"e", b"d", b"r"
GOAL, OUTCOME = b"g", b"o"  # a goal's frames (goal_server.py)
_SMALL = 64 * 1024  # payloads up to this size go out in one write with their header


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


def send_frames(sock: socket.socket, frames: list[tuple[bytes, int, bytes]]) -> None:
    """Frames of a relay's stream, in one write where they are small (a fast topic's messages are sent in
    batches: one system call for many)."""
    parts: list[bytes] = []
    try:
        for kind, stamp_ns, payload in frames:
            if len(payload) > MAX_SAMPLE:
                raise WireError(f"a frame of {len(payload)} bytes is over the {MAX_SAMPLE}-byte limit")
            parts.append(_FRAME.pack(len(payload), kind, stamp_ns))
            if len(payload) <= _SMALL:
                parts.append(payload)
                continue
            sock.sendall(b"".join(parts))
            sock.sendall(payload)
            parts.clear()
        if parts:
            sock.sendall(b"".join(parts))
    except OSError as err:
        raise WireError(f"cannot send: {err}") from None


def receive_frame(stream: BinaryIO) -> tuple[bytes, int, bytes]:
    """(kind, receive time in ns, payload) of a relay's next frame, from the connection's buffered reader
    (`sock.makefile("rb")`: many small frames in one system call)."""
    size, kind, stamp = _FRAME.unpack(_read(stream, _FRAME.size))
    if size > MAX_SAMPLE:
        raise WireError(f"a frame of {size} bytes is over the {MAX_SAMPLE}-byte limit")
    return kind, stamp, _read(stream, size)


def _read(stream: BinaryIO, size: int) -> bytes:
    try:
        data = stream.read(size)
    except (OSError, ValueError) as err:  # ValueError: the reader was closed
        raise WireError(f"cannot receive: {err or 'timed out'}") from None
    if data is None or len(data) < size:
        raise WireError("closed before the message ended")
    return data


def _exactly(sock: socket.socket, size: int) -> bytes:
    buffer = bytearray(size)
    view = memoryview(buffer)
    done = 0
    while done < size:
        try:
            count = sock.recv_into(view[done:], min(size - done, 1 << 20))
        except OSError as err:  # socket.timeout included
            raise WireError(f"cannot receive: {err or 'timed out'}") from None
        if not count:
            raise WireError("closed before the message ended")
        done += count
    return bytes(buffer)
