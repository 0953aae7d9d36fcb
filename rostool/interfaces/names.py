"""Type-name spellings: ROS 1 `pkg/Type`, ROS 2 / rosbags `pkg/msg/Type`."""

from __future__ import annotations


def to_store_name(name: str, kind: str = "msg") -> str:
    """`std_msgs/String` -> `std_msgs/msg/String` (already-qualified names pass through)."""
    parts = name.strip("/").split("/")
    if len(parts) == 2:
        return f"{parts[0]}/{kind}/{parts[1]}"
    return "/".join(parts)


def to_ros1_name(name: str) -> str:
    """`std_msgs/msg/String` -> `std_msgs/String`."""
    parts = name.split("/")
    if len(parts) == 3:
        return f"{parts[0]}/{parts[2]}"
    return name


def hidden_name(name: str) -> bool:
    """ros2cli hides names with a token starting with `_` (e.g. actions' `/x/_action/send_goal`)."""
    return any(token.startswith("_") for token in name.split("/"))
