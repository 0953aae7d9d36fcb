"""`ros2 topic echo`'s text of a message: truncation (`-l`, 128 by default), `--no-arr`, `--no-str`,
`--flow-style`, `--csv` and `--field`, as rosidl_runtime_py prints them.

Values follow rclpy's Python types: `byte` fields print as one-character strings, `char` as numbers,
arrays and sequences are abbreviated with their IDL element type (`boolean`, `octet`, `float`, `double`,
`pkg/msg/Type`). The field types come from the type store's definitions (`fielddefs`); without them the
value's own Python type decides.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import yaml

from rostool.output.plain import field_names, is_message

_IDL_NAMES = {"bool": "boolean", "byte": "octet", "char": "uint8", "float32": "float", "float64": "double"}
BASE, NAME, ARRAY, SEQUENCE = 1, 2, 3, 4  # rosbags' Nodetype values

Lookup = Callable[[str], Any]
_EVENT_INFO = "service_msgs/msg/ServiceEventInfo"
_EVENT_TYPES = {0: "REQUEST_SENT", 1: "REQUEST_RECEIVED", 2: "RESPONSE_SENT", 3: "RESPONSE_RECEIVED"}


@dataclass
class Ros2EchoOptions:
    truncate_length: int | None = 128
    no_arr: bool = False
    no_str: bool = False
    flow_style: bool = False


def fielddefs_lookup(fielddefs: Mapping[str, Any]) -> Lookup:
    """msgtype -> [(name, desc), ...] from a rosbags typestore's `fielddefs`."""

    def fields(msgtype: str) -> Any:
        found = fielddefs.get(msgtype)
        return None if found is None else dict(found[1])

    return fields


def _element_name(desc: Any) -> str:
    kind, detail = desc
    if kind == BASE:
        return _IDL_NAMES.get(detail[0], detail[0])
    return str(detail)  # NAME: the nested type, pkg/msg/Type


def _abbreviated(value: Any, desc: Any) -> str:
    kind, (element, size) = desc
    name = _element_name(element)
    if kind == ARRAY:
        return f"<array type: {name}[{size}]>"
    if size:
        return f"<sequence type: {name}[{size}], length: {len(value)}>"
    return f"<sequence type: {name}, length: {len(value)}>"


def _is_byte(desc: Any) -> bool:
    return desc is not None and desc[0] == BASE and desc[1][0] == "byte"


def _element_desc(desc: Any) -> Any:
    return desc[1][0] if desc is not None and desc[0] in (ARRAY, SEQUENCE) else None


def convert(value: Any, opts: Ros2EchoOptions, lookup: Lookup, desc: Any = None) -> Any:
    """A message or field value as the plain values ros2 topic echo dumps."""
    limit = opts.truncate_length
    if is_message(value):
        msgtype = getattr(value, "__msgtype__", "")
        fields = lookup(msgtype) or {}
        plain = {
            name: convert(getattr(value, name), opts, lookup, fields.get(name))
            for name in field_names(type(value))
        }
        if msgtype == _EVENT_INFO:  # ros2 service echo names the event (REQUEST_SENT, ...)
            plain["event_type"] = _EVENT_TYPES.get(plain["event_type"], plain["event_type"])
        return plain
    if _is_byte(desc) and isinstance(value, int):
        return chr(value)
    if isinstance(value, (bytes, bytearray)):
        text = "".join(chr(c) for c in value)
        return text[:limit] + "..." if limit is not None and len(text) > limit else text
    if isinstance(value, str):
        if opts.no_str:
            return f"<string length: <{len(value)}>>"
        return value[:limit] + "..." if limit is not None and len(value) > limit else value
    if hasattr(value, "tolist") and not hasattr(value, "__len__"):  # numpy scalar
        return value.tolist()
    if hasattr(value, "__len__"):
        if opts.no_arr and desc is not None and desc[0] in (ARRAY, SEQUENCE):
            return _abbreviated(value, desc)
        items = value.tolist() if hasattr(value, "tolist") else list(value)
        element = _element_desc(desc)
        if limit is not None and len(items) > limit:
            return [convert(v, opts, lookup, element) for v in items[:limit]] + ["..."]
        return [convert(v, opts, lookup, element) for v in items]
    return value


def to_yaml(value: Any, opts: Ros2EchoOptions, lookup: Lookup) -> str:
    """The YAML of a message (without the `---` line), as rosidl_runtime_py's message_to_yaml."""
    return yaml.dump(
        convert(value, opts, lookup), allow_unicode=True, width=sys.maxsize,
        default_flow_style=opts.flow_style, sort_keys=False,
    ).rstrip("\n")  # fmt: skip


def field_text(value: Any, opts: Ros2EchoOptions, lookup: Lookup) -> str:
    """One selected field: a message as YAML, anything else as Python prints it."""
    if is_message(value) or (hasattr(value, "__len__") and not isinstance(value, (str, bytes))):
        return to_yaml(value, opts, lookup)
    plain = convert(value, opts, lookup)
    return str(plain)


def to_csv(value: Any, opts: Ros2EchoOptions, lookup: Lookup, desc: Any = None) -> str:
    """Comma-separated values of every field, recursively, as rosidl_runtime_py's message_to_csv."""
    limit = opts.truncate_length
    if is_message(value):
        fields = lookup(getattr(value, "__msgtype__", "")) or {}
        return ",".join(
            to_csv(getattr(value, n), opts, lookup, fields.get(n)) for n in field_names(type(value))
        )
    if _is_byte(desc) and isinstance(value, int):
        return str(bytes([value]))
    if isinstance(value, str):
        if opts.no_str:
            return f"<string length: <{len(value)}>>"
        return value[:limit] + "..." if limit is not None and len(value) > limit else value
    if hasattr(value, "tolist") and not hasattr(value, "__len__"):
        return str(value.tolist())
    if hasattr(value, "__len__"):
        if opts.no_arr and desc is not None and desc[0] in (ARRAY, SEQUENCE):
            return _abbreviated(value, desc)
        items = value.tolist() if hasattr(value, "tolist") else list(value)
        parts = [
            to_csv(v, opts, lookup, _element_desc(desc))
            for v in items[: limit if limit is not None else None]
        ]
        if limit is not None and len(items) > limit:
            parts.append("...")
        return ",".join(parts)
    return str(value)
