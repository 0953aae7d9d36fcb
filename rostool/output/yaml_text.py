"""YAML text of messages, as the classic tools print it.

`ros1` style follows genpy's strify_message (what `rostopic echo` prints: `data: "hi"`, `header: ` with a
trailing space, time as secs/nsecs with nsecs right-aligned to 9 characters, Python `True`/`False`).
`ros2` style follows `ros2 topic echo` (plain YAML, sec/nanosec, block lists).
genpy cannot render rosbags' message objects, so this is written here.
"""

from __future__ import annotations

import re
from typing import Any

import yaml

from rostool.output.plain import TIME_TYPES, TimeStyle, field_names, is_message, to_plain

_SIMPLE_STRING = re.compile(r"[ -!#-\[\]-~]{1,60}")


def _quote(text: str) -> str:
    if not text:
        return "''"
    if _SIMPLE_STRING.fullmatch(text) and not text.startswith(" ") and not text.endswith(" "):
        return f'"{text}"'
    return yaml.dump(text, default_style='"').rstrip("\n")


def _scalar_list(values: list[Any]) -> str:
    return str(values)


def _ros1(value: object, indent: str) -> str:
    if is_message(value):
        if getattr(value, "__msgtype__", "") in TIME_TYPES:
            sec, nsec = value.sec, value.nanosec  # type: ignore[attr-defined]
            return f"\n{indent}secs: {sec}\n{indent}nsecs: {nsec:9d}"
        inner = "  " + indent
        lines = "\n".join(
            f"{indent}{name}: {_ros1(getattr(value, name), inner)}" for name in field_names(type(value))
        )
        return "\n" + lines if indent else lines
    if isinstance(value, str):
        return _quote(value)
    if isinstance(value, (bool, int, float)):
        return str(value)
    if hasattr(value, "tolist"):
        items = value.tolist()
        return "[]" if not items else _scalar_list(items) if isinstance(items, list) else str(items)
    if isinstance(value, (bytes, bytearray, memoryview)):
        return str(list(bytes(value))) if value else "[]"
    if isinstance(value, (list, tuple)):
        if not value:
            return "[]"
        first = value[0]
        if isinstance(first, str):
            dumped = yaml.dump(list(value)).rstrip("\n")
            if dumped.startswith("["):
                return dumped
            return "\n" + "\n".join(indent + line for line in dumped.splitlines())
        if isinstance(first, (bool, int, float)):
            return str(list(value))
        inner = indent + "  "
        return "\n" + "\n".join(f"{indent}- {_ros1(item, inner)}" for item in value)
    return str(value)


def to_yaml(msg: object, style: TimeStyle = "ros1") -> str:
    """The YAML block for one message (without the `---` separator)."""
    if style == "ros1":
        return _ros1(msg, "")
    plain = to_plain(msg, "ros2")
    if not isinstance(plain, dict):
        return yaml.safe_dump(plain, default_flow_style=False, allow_unicode=True).rstrip("\n")
    return yaml.safe_dump(plain, sort_keys=False, default_flow_style=False, allow_unicode=True).rstrip("\n")


def value_to_yaml(value: object, style: TimeStyle = "ros1") -> str:
    """YAML text for a selected field: a message, a list or a scalar."""
    if style == "ros1":
        text = _ros1(value, "")
        return text.lstrip("\n")
    return (
        yaml.safe_dump(to_plain(value, "ros2"), default_flow_style=False, allow_unicode=True)
        .rstrip("\n")
        .removesuffix("\n...")
    )


def param_yaml(value: Any) -> str:
    """YAML of a parameter value as rosparam writes it; PyYAML's document-end marker after scalars is
    dropped."""
    text = yaml.safe_dump(value, default_flow_style=False)
    return text[:-5] if text.endswith("\n...\n") else text
