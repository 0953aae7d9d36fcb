"""Nodes' log output and logger levels, for ROS 1 and ROS 2 alike, through the Graph protocol's
`subscribe`, `services` and `service_call`.

- Log messages: ROS 2 nodes publish rcl_interfaces/msg/Log on /rosout; ROS 1 nodes publish
  rosgraph_msgs/Log on /rosout, which roscore's rosout node gathers on /rosout_agg. The two types carry the
  same facts (stamp, level, name, msg, file, function, line) with different level numbers.
- Logger levels: ROS 1 nodes (roscpp and rospy) serve `<node>/get_loggers` and `<node>/set_logger_level`
  (roscpp/GetLoggers, roscpp/SetLoggerLevel, levels as lowercase names). ROS 2 nodes created with
  `enable_logger_service=True` serve `<node>/get_logger_levels` and `<node>/set_logger_levels`
  (rcl_interfaces, levels as numbers); they cannot list their loggers, so a ROS 2 node's list is its own
  logger (named after the node: `/ns/talker` logs as `ns.talker`).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import Received, Subscription

LEVELS = ("debug", "info", "warn", "error", "fatal")
_ROS2_LEVELS = {"debug": 10, "info": 20, "warn": 30, "error": 40, "fatal": 50}
_ROS1_LEVELS = {"debug": 1, "info": 2, "warn": 4, "error": 8, "fatal": 16}
GET_LEVELS = "rcl_interfaces/srv/GetLoggerLevels"
SET_LEVELS = "rcl_interfaces/srv/SetLoggerLevels"


def level_name(value: str) -> str:
    """A level as given on the command line (any case, `warning` too) -> one of LEVELS."""
    name = value.strip().lower().removesuffix("ing")
    if name not in LEVELS:
        raise RostoolError(f"unknown log level {value!r}: use one of {', '.join(LEVELS)}")
    return name


@dataclass(frozen=True)
class LogEntry:
    stamp_ns: int
    level: str  # one of LEVELS (upper case in output), or the number when a node sent another
    name: str  # ROS 1: the node; ROS 2: the logger (the node's, or a child of it)
    msg: str
    file: str
    function: str
    line: int

    def as_dict(self) -> dict[str, Any]:
        return {"stamp": self.stamp_ns / 1e9, "level": self.level.upper(), "name": self.name, "msg": self.msg,
                "file": self.file, "function": self.function, "line": self.line}  # fmt: skip


def log_topic(graph: Any) -> str:
    """ROS 2 /rosout; ROS 1 /rosout_agg, or /rosout itself where no rosout node gathers it (`rostool
    core` runs none)."""
    if graph.style == "ros2":
        return "/rosout"
    gathered = any(t.name == "/rosout_agg" and t.publishers for t in graph.topics())
    return "/rosout_agg" if gathered else "/rosout"


def to_entry(message: Any, style: str) -> LogEntry:
    """A decoded rcl_interfaces/msg/Log (ROS 2) or rosgraph_msgs/Log (ROS 1) as a LogEntry."""
    stamp = message.stamp if style == "ros2" else message.header.stamp
    levels = _ROS2_LEVELS if style == "ros2" else _ROS1_LEVELS
    number = int(message.level)
    level = next((name for name, value in levels.items() if value == number), str(number))
    stamp_ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
    return LogEntry(
        stamp_ns, level, str(message.name), str(message.msg), str(message.file), str(message.function),
        int(message.line),
    )  # fmt: skip


def node_logger_name(node: str) -> str:
    """The logger a ROS 2 node logs with: its full name without the leading slash, dots for slashes."""
    return node.strip("/").replace("/", ".")


def entry_filter(style: str, min_level: str, node: str | None) -> Callable[[LogEntry], bool]:
    """Keep entries at `min_level` or above, and (given a node) from that node (ROS 2: its logger and the
    loggers under it)."""
    rank = LEVELS.index(min_level)
    wanted = None if node is None else ("/" + node.strip("/") if style == "ros1" else node_logger_name(node))

    def keep(entry: LogEntry) -> bool:
        if entry.level in LEVELS and LEVELS.index(entry.level) < rank:
            return False
        if wanted is None:
            return True
        return entry.name == wanted or (style == "ros2" and entry.name.startswith(wanted + "."))

    return keep


def follow_log(graph: Any, on_entry: Callable[[LogEntry], None], topic: str | None = None) -> Subscription:
    """Subscribe to the graph's log topic (or `topic`); each message is given to `on_entry`."""

    def on_message(received: Received) -> None:
        on_entry(to_entry(received.decode(), graph.style))

    return graph.subscribe(topic or log_topic(graph), on_message)


# --- logger levels ------------------------------------------------------------------------------------
def _logger_services(graph: Any, node: str) -> tuple[str, str]:
    """The node's (get, set) logger services; one clear line when it offers none."""
    resolved = graph.resolve(node)
    base = resolved.rstrip("/")
    pair = (f"{base}/get_logger_levels", f"{base}/set_logger_levels")
    if graph.style == "ros1":
        pair = (f"{base}/get_loggers", f"{base}/set_logger_level")
    offered = {name for name, _type, _nodes in graph.services()}
    if pair[0] in offered and pair[1] in offered:
        return pair
    if resolved not in graph.node_names():
        raise RostoolError(f"unknown node {resolved} (see `rostool node list`)")
    how = "rospy and roscpp nodes serve them" if graph.style == "ros1" else (
        "a ROS 2 node serves them when created with enable_logger_service=True"
    )  # fmt: skip
    raise RostoolError(f"node {resolved} offers no logger services ({pair[0]}): {how}")


def logger_levels(graph: Any, node: str, names: list[str] | None = None) -> dict[str, str]:
    """Logger -> level name of `node` (ROS 1: every logger; ROS 2: `names`, by default its own logger)."""
    get, _set = _logger_services(graph, node)
    if graph.style == "ros1":
        _request, response = graph.service_call(get, ())
        return {str(lg.name): str(lg.level).lower() for lg in response.loggers}
    names = names or [node_logger_name(graph.resolve(node))]
    _request, response = graph.service_call(get, (GET_LEVELS, json.dumps({"names": names})))
    by_number = {number: name for name, number in _ROS2_LEVELS.items()}
    return {str(lg.name): by_number.get(int(lg.level), "unset") for lg in response.levels}


def default_logger(graph: Any, node: str, levels: dict[str, str] | None = None) -> str:
    """The logger a node's own messages go through: ROS 2 its node logger; ROS 1 rospy's `rosout`, else
    roscpp's root `ros`."""
    if graph.style == "ros2":
        return node_logger_name(graph.resolve(node))
    levels = levels if levels is not None else logger_levels(graph, node)
    return "rosout" if "rosout" in levels else "ros"


def set_logger_level(graph: Any, node: str, logger: str, level: str) -> None:
    _get, set_ = _logger_services(graph, node)
    if graph.style == "ros1":
        if logger not in logger_levels(graph, node):
            raise RostoolError(
                f"node {graph.resolve(node)} has no logger {logger} (see `rostool console list`)"
            )
        graph.service_call(set_, (json.dumps({"logger": logger, "level": level}),))
        return
    request = {"levels": [{"name": logger, "level": _ROS2_LEVELS[level]}]}
    _request, response = graph.service_call(set_, (SET_LEVELS, json.dumps(request)))
    result = response.results[0] if response.results else None
    if result is None or not result.successful:
        reason = result.reason if result is not None else "no result"
        raise RostoolError(f"node {graph.resolve(node)} refused level {level} for {logger}: {reason}")
