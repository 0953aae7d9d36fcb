"""What ros2 param get prints for a value: `Integer values are: [1, 2]`, or only the value (--hide-type)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

# Jazzy's ros2 param get prints integer and double arrays as lists (numpy's tolist()), byte arrays as
# rclpy's list of single bytes (a byte may arrive signed)
_ROS2_ARRAYS: dict[str, Callable[[Any], str]] = {
    "Integer values are": lambda v: repr([int(x) for x in v]),
    "Double values are": lambda v: repr([float(x) for x in v]),
    "Byte values are": lambda v: repr([bytes([x & 0xFF]) if isinstance(x, int) else bytes(x) for x in v]),
}


def get_text(value: Any, text: str, hide_type: bool) -> str:
    """ros2 param get's line for a value the backend showed as `text`."""
    label, sep, shown = text.partition(": ")
    if sep and label in _ROS2_ARRAYS:
        shown = _ROS2_ARRAYS[label](value)
    if not sep:
        return "None" if hide_type else text
    return shown if hide_type else f"{label}: {shown}"
