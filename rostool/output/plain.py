"""Message objects -> plain Python values (dicts in field order, lists, numbers, strings)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any, Literal

TimeStyle = Literal["ros1", "ros2"]

TIME_TYPES = ("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration")


def is_message(value: object) -> bool:
    return dataclasses.is_dataclass(value) and not isinstance(value, type)


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}


def field_names(cls: type) -> tuple[str, ...]:
    """A message class's field names in definition order, without rosbags' bookkeeping fields."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(
            f.name
            for f in dataclasses.fields(cls)
            if f.name != "structure_needs_at_least_one_member" and not f.name.startswith("__")
            and not str(f.type).startswith(("ClassVar", "typing.ClassVar"))  # a store's constants
        )  # fmt: skip
    return names


def message_fields(msg: object) -> Iterator[tuple[str, Any]]:
    """(name, value) of a message's fields in definition order (rosbags messages are dataclasses)."""
    for name in field_names(type(msg)):
        yield name, getattr(msg, name)


def time_parts(msg: object, style: TimeStyle) -> dict[str, int]:
    """A Time/Duration as ROS 1 (secs, nsecs) or ROS 2 (sec, nanosec) fields."""
    sec, nanosec = int(msg.sec), int(msg.nanosec)  # type: ignore[attr-defined]
    if style == "ros1":
        return {"secs": sec, "nsecs": nanosec}
    return {"sec": sec, "nanosec": nanosec}


def to_plain(value: object, style: TimeStyle = "ros1") -> Any:
    """Convert a message (or any field value) into JSON-ready Python values."""
    if is_message(value):
        if getattr(value, "__msgtype__", "") in TIME_TYPES:
            return time_parts(value, style)
        return {name: to_plain(field, style) for name, field in message_fields(value)}
    if hasattr(value, "tolist"):  # numpy arrays and numpy scalars
        return value.tolist()
    if isinstance(value, (bytes, bytearray, memoryview)):
        return list(bytes(value))
    if isinstance(value, (list, tuple)):
        return [to_plain(item, style) for item in value]
    return value


def select_field(value: object, path: str) -> object:
    """Follow a field path like `pose.position.x`, `ranges[0]` or `transforms/0/header`."""
    current = value
    for part in _split_path(path):
        if isinstance(part, int):
            try:
                current = current[part]  # type: ignore[index]
            except (IndexError, TypeError, KeyError) as err:
                raise LookupError(f"no index {part} in field path {path!r}") from err
        elif is_message(current) and hasattr(current, part):
            current = getattr(current, part)
        elif isinstance(current, dict) and part in current:
            current = current[part]
        else:
            raise LookupError(f"no field {part!r} in field path {path!r}")
    return current


def _split_path(path: str) -> list[str | int]:
    parts: list[str | int] = []
    for chunk in path.replace("/", ".").split("."):
        if not chunk:
            continue
        while "[" in chunk:
            head, _, rest = chunk.partition("[")
            index, _, chunk = rest.partition("]")
            if head:
                parts.append(head)
            parts.append(int(index))
        if chunk:
            parts.append(int(chunk) if chunk.lstrip("-").isdigit() else chunk)
    return parts


_NUMPY_TO_ROS = {
    "int8": "int8", "uint8": "uint8", "int16": "int16", "uint16": "uint16", "int32": "int32",
    "uint32": "uint32", "int64": "int64", "uint64": "uint64", "float32": "float32",
    "float64": "float64", "bool": "bool",
}  # fmt: skip


def _element_type(value: Any) -> str:
    dtype = getattr(value, "dtype", None)
    if dtype is not None:
        return _NUMPY_TO_ROS.get(str(dtype), str(dtype))
    if isinstance(value, (bytes, bytearray)):
        return "uint8"
    first = value[0] if len(value) else None
    if is_message(first):
        return str(getattr(first, "__msgtype__", "msg")).replace("/msg/", "/")
    return {bool: "bool", int: "int64", float: "float64", str: "string"}.get(type(first), "unknown")


def elide(msg: object, noarr: bool, nostr: bool) -> object:
    """Replace arrays and/or strings by short placeholders, as `rostopic echo --noarr/--nostr` do."""
    if not is_message(msg) or getattr(msg, "__msgtype__", "") in TIME_TYPES:
        return msg
    changes: dict[str, Any] = {}
    for name, value in message_fields(msg):
        if isinstance(value, str):
            if nostr:
                changes[name] = f"<string length: {len(value)}>"
        elif hasattr(value, "__len__") and not is_message(value):
            if noarr or (nostr and value and isinstance(value[0], str)):
                changes[name] = f"<array type: {_element_type(value)}, length: {len(value)}>"
        elif is_message(value):
            changes[name] = elide(value, noarr, nostr)
    return dataclasses.replace(msg, **changes) if changes else msg  # type: ignore[type-var]
