"""Small helpers every command shares."""

from __future__ import annotations

import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, Literal

import click

if TYPE_CHECKING:
    from rostool.graph.base import Graph


def ros_version(ctx: click.Context) -> int | None:
    settings = ctx.find_root().obj
    return getattr(settings, "ros_version", None)


def interface_style(ctx: click.Context, type_name: str = "") -> Literal["ros1", "ros2"]:
    """Whose forms the interface verbs (msg, srv, action show) follow; they need no graph."""
    from rostool.interfaces.describe_ros2 import ros2_selected

    return "ros2" if ros2_selected(ros_version(ctx), type_name) else "ros1"


@contextmanager
def live_graph(ctx: click.Context, interface_paths: Sequence[str] = ()) -> Iterator[Graph]:
    """The selected live graph, always closed (unregistered) on the way out, Ctrl+C included."""
    from rostool.graph import open_graph

    graph = open_graph(ros_version(ctx), interface_paths=interface_paths)
    try:
        yield graph
    finally:
        graph.close()


def print_json(value: Any) -> None:
    from rostool.output.json_text import dumps

    click.echo(dumps(value))


def stdout_is_tty() -> bool:
    return sys.stdout.isatty()


json_option = click.option("--json", "as_json", is_flag=True, help="Print JSON for scripts.")

interfaces_option = click.option(
    "--interfaces",
    "interface_paths",
    multiple=True,
    type=click.Path(exists=True),
    envvar="ROSTOOL_INTERFACES",
    help="Also find .msg/.srv/.action files here: a workspace, a package or one file (repeatable; "
    "env ROSTOOL_INTERFACES). ROS_PACKAGE_PATH and the workspace around the current folder are searched too.",
)
