"""Text of a type as `rosmsg show` prints it: constants, then fields with nested types indented."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rosbags.interfaces import Nodetype

from rostool.interfaces.names import to_ros1_name

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

_ROS1_TIME = {"builtin_interfaces/msg/Time": "time", "builtin_interfaces/msg/Duration": "duration"}


def _type_text(kind: int, args: Any) -> tuple[str, str | None]:
    """(text of the field type, nested message type to expand or None)."""
    if kind == Nodetype.BASE:
        name, bound = args
        return (f"string<={bound}" if name == "string" and bound else name), None
    if kind == Nodetype.NAME:
        nested = str(args)
        if nested in _ROS1_TIME:
            return _ROS1_TIME[nested], None
        return to_ros1_name(nested), nested
    (sub_kind, sub_args), length = args
    inner, nested_name = _type_text(sub_kind, sub_args)
    size = "" if not length else str(length) if kind == Nodetype.ARRAY else f"<={length}"
    return f"{inner}[{size}]", nested_name


def describe(store: Typestore, type_name: str, indent: str = "") -> list[str]:
    consts, fields = store.fielddefs[type_name]
    lines = [f"{indent}{ctype} {name}={value}" for name, ctype, value in consts]
    for name, (kind, args) in fields:
        if name == "structure_needs_at_least_one_member":
            continue
        text, nested = _type_text(kind, args)
        lines.append(f"{indent}{text} {name}")
        if nested is not None:
            lines.extend(describe(store, nested, indent + "  "))
    return lines
