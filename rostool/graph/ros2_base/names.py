"""ROS 2 names <-> DDS names, as rmw_cyclonedds_cpp and rmw_fastrtps_cpp mangle them (ROS 2 design
article "Topic and Service name mapping to DDS"):

- topic `/chatter` -> DDS topic `rt/chatter`; service `/add` -> `rq/addRequest` and `rr/addReply`;
- type `std_msgs/msg/String` -> DDS type `std_msgs::msg::dds_::String_` (nested types likewise);
- the graph topic `ros_discovery_info` has no prefix (avoid_ros_namespace_conventions).
"""

from __future__ import annotations

from rostool.errors import RostoolError

TOPIC_PREFIX = "rt"
REQUEST_PREFIX = "rq"
REPLY_PREFIX = "rr"
UNKNOWN_NODE = "_NODE_NAME_UNKNOWN_"  # what ros2cli prints for endpoints no node claims


def resolve(name: str, node: str = "/rostool") -> str:
    """Fully qualify a name the way ros2cli does for a node in the root namespace."""
    name = name.strip()
    if not name:
        raise RostoolError("empty name: give a topic or node name such as /chatter")
    if name.startswith("~"):
        name = node.rstrip("/") + "/" + name[1:].lstrip("/")
    if not name.startswith("/"):
        name = "/" + name
    while "//" in name:
        name = name.replace("//", "/")
    return name.rstrip("/") or "/"


def topic_to_dds(topic: str) -> str:
    return TOPIC_PREFIX + resolve(topic)


def request_topic(service: str) -> str:
    return REQUEST_PREFIX + resolve(service) + "Request"


def reply_topic(service: str) -> str:
    return REPLY_PREFIX + resolve(service) + "Reply"


def from_dds_topic(dds_name: str) -> tuple[str, str] | None:
    """('topic' | 'request' | 'reply', ROS name) for a ROS-mangled DDS topic, else None."""
    prefix, slash, rest = dds_name.partition("/")
    if not slash:
        return None
    if prefix == TOPIC_PREFIX:
        return "topic", "/" + rest
    if prefix == REQUEST_PREFIX and rest.endswith("Request"):
        return "request", "/" + rest.removesuffix("Request")
    if prefix == REPLY_PREFIX and rest.endswith("Reply"):
        return "reply", "/" + rest.removesuffix("Reply")
    return None


def type_to_dds(store_name: str) -> str:
    """`pkg/msg/Type` -> `pkg::msg::dds_::Type_`."""
    parts = store_name.split("/")
    return "::".join(parts[:-1]) + "::dds_::" + parts[-1] + "_"


def from_dds_type(dds_type: str) -> str:
    """`pkg::msg::dds_::Type_` -> `pkg/msg/Type`; other names pass through unchanged."""
    parts = dds_type.split("::")
    if len(parts) >= 3 and parts[-2] == "dds_" and parts[-1].endswith("_"):
        return "/".join([*parts[:-2], parts[-1][:-1]])
    return dds_type


def service_type(request_or_reply_type: str) -> str:
    """`pkg/srv/Name_Request` (or `_Response`) -> `pkg/srv/Name`."""
    for suffix in ("_Request", "_Response"):
        if request_or_reply_type.endswith(suffix):
            return request_or_reply_type.removesuffix(suffix)
    return request_or_reply_type
