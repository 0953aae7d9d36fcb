"""Messages as rclpy's repr prints them (what `ros2 service call` and `ros2 topic pub` show)."""

from __future__ import annotations

from typing import Any

from rostool.output.plain import is_message, message_fields


def message_repr(value: Any, lookup: Any = None, desc: Any = None) -> str:
    """A message as rclpy's repr shows it: `pkg.srv.Name_Request(a=1, b=2)`; with the type store's field
    lookup, `byte` fields print as bytes (b'\\x00') as rclpy's do."""
    if is_message(value):
        msgtype = getattr(value, "__msgtype__", type(value).__name__)
        descs = (lookup(msgtype) if lookup else None) or {}
        fields = ", ".join(f"{k}={message_repr(v, lookup, descs.get(k))}" for k, v in message_fields(value))
        return f"{msgtype.replace('/', '.')}({fields})"
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        element = desc[1][0] if desc is not None and desc[0] in (3, 4) else None  # array, sequence
        return "[" + ", ".join(message_repr(v, lookup, element) for v in value) + "]"
    if isinstance(value, int) and desc is not None and desc[0] == 1 and desc[1][0] == "byte":
        return repr(bytes([value]))
    return repr(value)
