"""Shell completion: topic, node, service, action, parameter and type names, bag files and bag topics.

`attach(command)` runs on every command the root group loads (cli.LazyGroup, _common.ExtensibleGroup) and
gives its text arguments and options click's `shell_complete` callback. What a parameter names is decided
when it is completed, from the command path and the parameter's metavar (TOPIC, NODE, SERVICE, ACTION,
PARAM, TYPE, BAG, FILE, DIR...) or, where the metavar does not say, from `_BY_NAME`.

Completion is best effort and must never get in the way: attaching imports nothing; a graph that does not
answer within the budget (ROSTOOL_COMPLETE_TIMEOUT, else 0.5 s for a ROS 1 master, 2 s for ROS 2
discovery) gives no candidates; nothing is written to stderr (it would garble the prompt).
"""

from __future__ import annotations

import atexit
import contextlib
import io
import os
import re
import sys
import threading
from collections.abc import Iterable, Iterator
from typing import Any

import click
from click.shell_completion import CompletionItem

COMPLETE_ENV = "_ROSTOOL_COMPLETE"  # set by the shell scripts click generates (`rostool` -> _ROSTOOL_...)
TIMEOUT_ENV = "ROSTOOL_COMPLETE_TIMEOUT"
# A ROS 1 master answers at once. ROS 2 needs DDS discovery: a Fast DDS peer's endpoints reach the DDS
# backend in about 1.3 s (its next heartbeat), rclpy's graph in about 1 s; node names on the DDS backend can
# take up to 3 s (ros_discovery_info comes a heartbeat later), which ROSTOOL_COMPLETE_TIMEOUT can allow.
BUDGET_SECONDS = {1: 0.5, 2: 2.0}

# What an upper-case word of a metavar names. TYPE is refined by command (msg, srv or action types).
_METAVAR_KINDS = {
    "TOPIC": "topic", "T": "topic", "NODE": "node", "SERVICE": "service", "ACTION": "action",
    "PARAM": "param", "TYPE": "type", "MSG": "msg", "SRV": "srv", "BAG": "file", "FILE": "file",
    "IN": "file", "OUT": "file", "SRC": "file", "DST": "file", "DIR": "dir",
}  # fmt: skip

# (command path..., parameter name) -> kind, or (kind under ROS 1, kind under ROS 2) where rosparam's and
# ros2 param's forms differ; None: no completion where a metavar word would mislead.
Kind = str | tuple[str | None, str | None] | None
_BY_NAME: dict[tuple[str, ...], Kind] = {
    **{("topic", verb, "name"): "topic" for verb in ("echo", "info", "type", "bw", "delay", "pub")},
    ("topic", "echo", "message_type"): "msg",
    ("topic", "pub", "type_name"): "msg",
    ("topic", "plot", "paths"): "topic",
    ("node", "info", "name"): "node",
    ("node", "ping", "name"): "node",
    ("param", "list", "namespace"): ("param", "node"),
    ("param", "get", "name"): ("param", "node"),
    ("param", "get", "param_name"): (None, "param"),
    ("param", "set", "name"): ("param", "node"),
    ("param", "set", "value"): (None, "param"),
    ("param", "set", "more"): None,
    ("param", "delete", "name"): ("param", "node"),
    ("param", "delete", "param_names"): (None, "param"),
    ("param", "describe", "node"): "node",
    ("param", "dump", "file"): ("file", "node"),
    ("param", "dump", "namespace"): ("param", "file"),
    ("param", "load", "file"): ("file", "node"),
    ("param", "load", "namespace"): ("param", "file"),
    ("action", "send-goal", "values"): "action_type",
    ("action", "cancel", "name"): "action",
    ("bag", "echo", "args"): "bag_args",
    ("bag", "plot", "paths"): "bag_topic",
}
_FIRST_VALUE_ONLY = {("action", "send-goal", "values")}  # NAME TYPE GOAL: only the TYPE is completed
_BAG_SOURCES = ("bag_path", "bags", "args", "paths", "inputs", "files")  # parameters that hold bags
_GRAPH_KINDS = ("topic", "node", "service", "action", "param")
_TYPE_KINDS = ("msg", "srv", "action_type")

_workers: list[threading.Thread] = []
_quieted = False


def attach(command: click.Command) -> None:
    """Give `command` (and a group's subcommands) the completion callback; cheap and idempotent."""
    for param in command.params:
        if _completable(param):
            param._custom_shell_complete = _complete
    if isinstance(command, click.Group):
        for sub in command.commands.values():
            attach(sub)


def _completable(param: click.Parameter) -> bool:
    if param._custom_shell_complete not in (None, _complete):
        return False  # the command chose its own
    if isinstance(param, click.Option) and (param.is_flag or param.count):
        return False
    return isinstance(param.type, (click.types.StringParamType, click.types.UnprocessedParamType))


def _complete(ctx: click.Context, param: click.Parameter, incomplete: str) -> list[CompletionItem]:
    try:
        with _quiet():
            return _items(ctx, param, incomplete)
    except Exception:
        return []


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Nothing on stderr. In the shell (`_ROSTOOL_COMPLETE` set) the process only completes, so fd 2 goes
    to /dev/null for good (native DDS and rcl logs too) and the process ends without waiting for a lookup
    still running past its budget; in-process (click's ShellComplete API) Python's stderr is captured."""
    global _quieted
    if os.environ.get(COMPLETE_ENV):
        if not _quieted:
            _quieted = True
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 2)
            atexit.register(_exit_now)  # registered last, so it runs before the libraries' own handlers
        yield
        return
    with contextlib.redirect_stderr(io.StringIO()):
        yield


def _exit_now() -> None:
    for worker in _workers:
        worker.join(timeout=0.5)  # a lookup that answered is closing its graph (unregistering)
    with contextlib.suppress(Exception):
        sys.stdout.flush()
    os._exit(0)


def _items(ctx: click.Context, param: click.Parameter, incomplete: str) -> list[CompletionItem]:
    path = _command_path(ctx)
    kind = _kind(ctx, path, param)
    if kind is None:
        return []
    if kind in ("file", "dir"):
        return [CompletionItem(incomplete, type=kind)]
    if kind == "bag_args":
        return _bag_args(ctx, incomplete)
    if kind in _TYPE_KINDS:
        found = _matching_types(kind, _type_version(ctx, path, incomplete), incomplete)
    elif kind == "bag_topic":
        found = matching(_bag_topics(_bag_paths(ctx)), incomplete)
    else:
        found = matching(_from_graph(ctx, kind), incomplete)
    return [CompletionItem(name) for name in found]


def _command_path(ctx: click.Context) -> tuple[str, ...]:
    names: list[str] = []
    current: click.Context | None = ctx
    while current is not None and current.parent is not None:
        names.append(current.info_name or "")
        current = current.parent
    return tuple(reversed(names))


def _kind(ctx: click.Context, path: tuple[str, ...], param: click.Parameter) -> str | None:
    key = (*path, param.name or "")
    kind = _BY_NAME[key] if key in _BY_NAME else _metavar_kind(ctx, path, param)
    if isinstance(kind, tuple):
        kind = kind[_graph_version(ctx) - 1]
    if kind is not None and key in _FIRST_VALUE_ONLY and ctx.params.get(param.name or ""):
        return None
    return kind


def _metavar_kind(ctx: click.Context, path: tuple[str, ...], param: click.Parameter) -> str | None:
    words = re.findall(r"[A-Z][A-Z0-9_]*", param.metavar or "")
    kind = next((_METAVAR_KINDS[w] for w in words if w in _METAVAR_KINDS), None)
    has_bags = any(p.name in _BAG_SOURCES for p in ctx.command.params)
    if kind == "type":
        if path[:1] == ("srv",) or path == ("service", "find"):
            return "srv"
        return "action_type" if path == ("action", "show") else "msg"
    if path[:1] == ("bag",) and has_bags and kind in ("topic", "service"):
        return "bag_topic" if kind == "topic" else None  # a bag's topics, not the live graph's
    return kind


def matching(names: Iterable[str], incomplete: str) -> list[str]:
    """Names that start with `incomplete`; a relative start (`chat`) matches `/chatter` as `chatter`."""
    names = sorted(set(names))
    if incomplete and not incomplete.startswith("/"):
        relative = [n[1:] for n in names if n.startswith("/") and n[1:].startswith(incomplete)]
        return sorted({*relative, *(n for n in names if n.startswith(incomplete))})
    return [n for n in names if n.startswith(incomplete)]


# --- the live graph -----------------------------------------------------------------------------------
def _explicit_version(ctx: click.Context) -> int | None:
    # the root's callback (which fills ctx.obj) does not run while completing: read its parsed options
    version = ctx.find_root().params.get("ros_version")
    return version if version in (1, 2) else None


def _graph_version(ctx: click.Context) -> int:
    from rostool.graph import select_ros_version

    return select_ros_version(_explicit_version(ctx))


def budget(version: int) -> float:
    """Seconds a lookup may take: ROSTOOL_COMPLETE_TIMEOUT, else the version's default."""
    with contextlib.suppress(ValueError):
        given = float(os.environ.get(TIMEOUT_ENV, ""))
        if given > 0:
            return given
    return BUDGET_SECONDS[version]


def _from_graph(ctx: click.Context, kind: str) -> list[str]:
    """`kind` names of the selected live graph, or none when it does not answer within the budget. The
    lookup runs in a daemon thread: a master that hangs or a slow discovery is left behind, not waited
    for."""
    version = _graph_version(ctx)
    backend = ctx.find_root().params.get("ros2_backend")
    node = ctx.params.get("name") or ctx.params.get("node")
    found: list[str] = []
    answered = threading.Event()

    def lookup() -> None:
        graph = None
        try:
            from rostool.graph import open_graph

            graph = open_graph(version, node_name="rostool_complete", ros2_backend=backend)
            found.extend(_graph_names(graph, kind, node, budget(version)))
        except BaseException:  # completion offers nothing rather than an error
            pass
        finally:
            answered.set()
            if graph is not None:
                with contextlib.suppress(BaseException):
                    graph.close()

    worker = threading.Thread(target=lookup, name="rostool completion", daemon=True)
    _workers.append(worker)
    worker.start()
    if not answered.wait(budget(version)):
        return []
    return list(found)


def _graph_names(graph: Any, kind: str, node: str | None, timeout: float) -> list[str]:
    from rostool.interfaces.names import hidden_name

    if kind == "topic":
        names = [topic.name for topic in graph.topics()]
    elif kind == "node":
        names = list(dict.fromkeys(graph.node_names()))
    elif kind == "service":
        names = [name for name, _type, _nodes in graph.services()]
    elif kind == "action":
        names = [action.name for action in graph.actions()]
    elif kind == "param":
        if graph.style == "ros2" and not node:
            return []  # ros2 param: PARAM follows NODE
        return list(graph.parameters(node if graph.style == "ros2" else None, timeout).names())
    else:
        return []
    return [name for name in names if not hidden_name(name)]


# --- types --------------------------------------------------------------------------------------------
def _type_version(ctx: click.Context, path: tuple[str, ...], incomplete: str) -> int:
    """ROS 1 names (`std_msgs/String`) or ROS 2 names (`std_msgs/msg/String`): --ros1/--ros2, else a
    ROS 2 name being typed, else what the verb follows (the interface verbs never probe for a master)."""
    from rostool.interfaces.describe_ros2 import kind_of, ros2_selected

    explicit = _explicit_version(ctx)
    if explicit is not None:
        return explicit
    if kind_of(incomplete) is not None or incomplete.count("/") >= 2:
        return 2
    if path[:1] in (("msg",), ("srv",)) or path == ("action", "show"):
        return 2 if ros2_selected(None, incomplete) else 1
    return _graph_version(ctx)


def _matching_types(kind: str, version: int, incomplete: str) -> list[str]:
    """Type names starting with `incomplete`; under ROS 2 `pkg/Na` also finds `pkg/msg/Name`."""
    from rostool.interfaces.names import to_ros1_name

    names = _type_names(kind, version)
    if version == 2 and incomplete.count("/") == 1:
        return [n for n in names if n.startswith(incomplete) or to_ros1_name(n).startswith(incomplete)]
    return [n for n in names if n.startswith(incomplete)]


def _type_names(kind: str, version: int) -> list[str]:
    """Built-in type names (rosbags' stores, rostool's services and actions) and those of the interface
    sources rostool searches (ROSTOOL_INTERFACES, ROS_PACKAGE_PATH, the workspace)."""
    from rostool.interfaces.sources import interface_paths_from_env

    paths = interface_paths_from_env()
    if version == 2:
        from rostool.interfaces.describe_ros2 import Ros2Interfaces

        return Ros2Interfaces(paths).names({"msg": "msg", "srv": "srv", "action_type": "action"}[kind])
    from rostool.interfaces.names import to_ros1_name
    from rostool.interfaces.sources import interfaces

    catalog = interfaces(paths)
    if kind == "srv":
        from rostool.interfaces.srv import service_names

        return service_names(catalog)
    if kind == "action_type":
        from rostool.interfaces.action import action_names

        return action_names(catalog)
    from rostool.interfaces.ros1 import builtin_store

    store = [to_ros1_name(name) for name in builtin_store().fielddefs if "/msg/" in name]
    return sorted({*store, *catalog.source_names("msg")})


# --- bags ---------------------------------------------------------------------------------------------
def _bag_paths(ctx: click.Context) -> list[str]:
    """The bags already on the command line (the output of convert/filter does not exist yet)."""
    given: list[str] = []
    for name in _BAG_SOURCES:
        value = ctx.params.get(name)
        if isinstance(value, str):
            given.append(value)
        elif isinstance(value, (list, tuple)):
            given.extend(v for v in value if isinstance(v, str))
    # an option still missing its value (`BAG --topics <TAB>`) stops click's parsing before the
    # positional arguments, which are then left in ctx.args
    given.extend(arg for arg in ctx.args if isinstance(arg, str))
    return [path for path in dict.fromkeys(given) if _is_bag(path)]


def _is_bag(path: str) -> bool:
    from rostool.bag.open import detect

    try:
        detect(path)
    except Exception:
        return False
    return True


def _bag_topics(paths: list[str]) -> list[str]:
    from rostool.bag.reader import BagReader

    topics: set[str] = set()
    for path in paths:  # one at a time: ROS 1 and ROS 2 bags cannot be read together
        with contextlib.suppress(Exception), BagReader([path]) as reader:
            topics.update(reader.topics)
    return sorted(topics)


def _bag_args(ctx: click.Context, incomplete: str) -> list[CompletionItem]:
    """bag echo BAG... [TOPIC]...: the topics of the bags given so far, else files."""
    bags = _bag_paths(ctx)
    topics = matching(_bag_topics(bags), incomplete) if bags else []
    if topics:
        return [CompletionItem(topic) for topic in topics]
    return [CompletionItem(incomplete, type="file")]
