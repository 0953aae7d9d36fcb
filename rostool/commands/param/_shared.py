"""What the param verbs share: ros2 param's options, the refusals of one version's forms on the other's
graph, ros2 param set/delete's result line, and reading and writing files."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from rostool.commands._common import ignored_ros2_options
from rostool.errors import RostoolError
from rostool.graph.base import Graph

hidden_nodes_option = click.option(
    "--include-hidden-nodes", "include_hidden", is_flag=True, help="ROS 2: hidden nodes (_name) count too."
)
node_timeout_option = click.option(
    "--timeout", "node_timeout", type=click.FloatRange(min=0), default=1.0, show_default=True, metavar="S",
    help="ROS 2: seconds to wait for NODE to appear.",
)  # fmt: skip


def ros2_param_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """The options every ROS 2 param verb takes: hidden nodes, --timeout, and ros2cli's ignored ones."""
    for option in (ignored_ros2_options("no_daemon", "spin_time", "use_sim_time"), node_timeout_option,
                   hidden_nodes_option):  # fmt: skip
        func = option(func)
    return func


def ros2_only(graph: Graph, **given: Any) -> None:
    """Refuse ros2 param's flags on a ROS 1 graph (rosparam has none of them)."""
    used = [name for name, value in given.items() if value]
    if graph.style != "ros2" and used:
        flags = ", ".join("--" + name.replace("_", "-") for name in used)
        raise RostoolError(f"{flags} apply to ROS 2 parameters only (rostool --ros2 param ...)")


def ros2_only_args(graph: Graph, extra: str | None, usage: str) -> None:
    if graph.style == "ros2" and extra is None:
        raise RostoolError(f"ROS 2 parameters belong to a node: {usage}")
    if graph.style != "ros2" and extra is not None:
        raise RostoolError(f"too many arguments for a ROS 1 parameter ({usage} is the ROS 2 form)")


def report(ok: bool, outcome: str, reason: str, name: str, node: str, several: bool) -> bool:
    """ros2 param set/delete's line for one parameter (prefixed by its name when several are given); a
    single parameter's failure is the command's one error line."""
    line = outcome + (f": {reason}" if reason else "")
    if not several and not ok:
        raise RostoolError(f"{line} (parameter {name} of {node})")
    click.echo(f"{name}: {line}" if several else line, err=not ok)
    return ok


def json_text(value: Any) -> str:
    from rostool.output.json_text import dumps

    return dumps(value) + "\n"


def read_text(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError as err:
        raise RostoolError(f"cannot read {path}: {err.strerror}") from err


def write_text(file: str, text: str) -> None:
    """To stdout for "-", else to FILE whole or not at all."""
    if file == "-":
        click.echo(text, nl=False)
        return
    target = Path(file)
    temporary = target.with_name(f".{target.name}.tmp")
    try:
        temporary.write_text(text)
        temporary.replace(target)  # never leaves a half-written file behind
    except OSError as err:
        temporary.unlink(missing_ok=True)
        raise RostoolError(f"cannot write {file}: {err.strerror}") from err
