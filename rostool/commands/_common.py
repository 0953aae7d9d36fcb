"""Small helpers every command shares."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import click

if TYPE_CHECKING:
    from rostool.graph.base import Graph


@dataclass
class Settings:
    """Options given before the verb (`rostool --ros2 --ros2-backend dds ...`): the one context object every
    command reads through `settings(ctx)`."""

    ros_version: int | None = None
    ros2_backend: str | None = None  # auto | rclpy | dds; None: ROSTOOL_ROS2_BACKEND, else auto


def settings(ctx: click.Context) -> Settings:
    root = ctx.find_root()
    if isinstance(root.obj, Settings):
        return root.obj
    # shell completion (and a command invoked alone) parses the root's options without running its callback
    version = root.params.get("ros_version")
    return Settings(version if version in (1, 2) else None, root.params.get("ros2_backend"))


def ros_version(ctx: click.Context) -> int | None:
    return settings(ctx).ros_version


def ros2_backend(ctx: click.Context) -> str | None:
    return settings(ctx).ros2_backend


def interface_style(ctx: click.Context, type_name: str = "") -> Literal["ros1", "ros2"]:
    """Whose forms the interface verbs (msg, srv, action show) follow; they need no graph."""
    from rostool.interfaces.describe_ros2 import ros2_selected

    return "ros2" if ros2_selected(ros_version(ctx), type_name) else "ros1"


def open_live_graph(
    ctx: click.Context, interface_paths: Sequence[str] = (), node_name: str = "rostool"
) -> Graph:
    """The live graph the root options select; through the graph daemon unless the verb's `--no-daemon`; a
    direct ROS 2 listing waits the verb's `--spin-time` for discovery."""
    from rostool.graph import open_graph

    use_daemon = not ctx.params.get("no_daemon")
    spin_time = ctx.params.get("spin_time")
    return open_graph(
        ros_version(ctx), node_name, interface_paths, ros2_backend(ctx), use_daemon=use_daemon,
        spin_time=spin_time,
    )  # fmt: skip


@contextmanager
def live_graph(ctx: click.Context, interface_paths: Sequence[str] = ()) -> Iterator[Graph]:
    """The selected live graph, always closed (unregistered) on the way out, Ctrl+C included."""
    graph = open_live_graph(ctx, interface_paths)
    try:
        yield graph
    finally:
        graph.close()


def echo_names(names: Sequence[str], count: bool) -> None:
    """A find verb's answer: the names one a line (nothing at all for none), or with -c their number."""
    click.echo(str(len(names)) if count else "\n".join(names), nl=count or bool(names))


def announced_type_verb(
    kind: str,
    help_text: str,
    announced: Callable[[Graph], list[tuple[str, str | None]]],
    ros1_type: Callable[[Graph, str], str] | None = None,
) -> click.Command:
    """`service type` / `action type`: the type(s) the graph announces for NAME (`announced`: name, type
    pairs), else nothing on stdout and an error (exit 1), as ros2 service/action type; where ROS 1 asks the
    thing itself (`ros1_type`), that answer."""

    @click.command("type", help=help_text)
    @click.argument("name", metavar=kind.upper())
    @ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
    @click.pass_context
    def type_(ctx: click.Context, name: str) -> None:
        from rostool.errors import RostoolError

        with live_graph(ctx) as graph:
            if ros1_type is not None and graph.style == "ros1":
                click.echo(ros1_type(graph, name))
                return
            resolved = graph.resolve(name)
            pairs = announced(graph)
        types = sorted({type_name for found, type_name in pairs if found == resolved and type_name})
        if not types:
            raise RostoolError(f"unknown {kind} {resolved}: no server announces it (`rostool {kind} list`)")
        click.echo("\n".join(types))

    return type_


def print_json(value: Any) -> None:
    from rostool.output.json_text import dumps

    click.echo(dumps(value))


def stdout_is_tty() -> bool:
    return sys.stdout.isatty()


json_option = click.option("--json", "as_json", is_flag=True, help="Print JSON for scripts.")
# graph/publishing.match_known_subscribers: the first message waits for the subscribers the graph shows
# (the default is publishing.MATCH_WAIT_SECONDS, not imported here: every verb's start-up loads this module)
match_wait_option = click.option(
    "--match-wait", type=click.FloatRange(min=0), default=3.0, show_default=True, metavar="S",
    help="Wait at most S seconds for the subscribers the graph shows to match before the first message "
    "(0: do not wait).",
)  # fmt: skip


def warner(quiet: bool) -> Callable[[str], None]:
    """`rostool: warning: ...` lines on stderr, or nothing with -q."""
    if quiet:
        return lambda text: None
    return lambda text: click.echo(f"rostool: warning: {text}", err=True)


interfaces_option = click.option(
    "--interfaces",
    "interface_paths",
    multiple=True,
    type=click.Path(exists=True),
    envvar="ROSTOOL_INTERFACES",
    help="Also find .msg/.srv/.action files here: a workspace, a package or one file (repeatable; "
    "env ROSTOOL_INTERFACES). ROS_PACKAGE_PATH and the workspace around the current folder are searched too.",
)


def attach_completion(command: click.Command) -> click.Command:
    """Give the arguments live-graph and bag completion (rostool.completion), when that module exists."""
    from importlib.util import find_spec

    if find_spec("rostool.completion") is not None:
        from rostool.completion import attach

        attach(command)
    return command


class ExtensibleGroup(click.Group):
    """A command group whose verbs can live in their own modules, imported only when used.

    `extra`: verb -> "module:attribute", listed when the module exists (optional features, e.g. export).
    `ros2_forms`: verb -> "module:attribute" used instead of the group's own verb when the selected ROS
    version is 2 (ros2cli's flags where the letters mean something else than in the ROS 1 tool).
    """

    def __init__(
        self,
        *args: Any,
        extra: dict[str, str] | None = None,
        ros2_forms: dict[str, str] | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(*args, **kwargs)
        self.extra = extra or {}
        self.ros2_forms = ros2_forms or {}

    def list_commands(self, ctx: click.Context) -> list[str]:
        names = set(super().list_commands(ctx))
        names.update(name for name, spec in self.extra.items() if _spec_exists(spec))
        return sorted(names)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        spec = self.ros2_forms.get(cmd_name)
        if spec is not None and _spec_exists(spec) and _selected_version(ctx) == 2:
            return attach_completion(_load(spec))
        command = super().get_command(ctx, cmd_name)
        if command is None:
            spec = self.extra.get(cmd_name)
            if spec is None or not _spec_exists(spec):
                return None
            command = _load(spec)
        return attach_completion(command)


def _selected_version(ctx: click.Context) -> int:
    from rostool.graph import select_ros_version

    return select_ros_version(ros_version(ctx))


def _spec_exists(spec: str) -> bool:
    from importlib.util import find_spec

    return find_spec(spec.partition(":")[0]) is not None


def _load(spec: str) -> click.Command:
    import importlib

    module, _, attribute = spec.partition(":")
    command: click.Command = getattr(importlib.import_module(module), attribute)
    return command


spin_time_option = click.option(
    "--spin-time", type=click.FloatRange(min=0), metavar="S",
    help="ROS 2: seconds to wait for discovery when no graph daemon answers (or with --no-daemon), as "
    "ros2cli; default: until discovery settles.",
)  # fmt: skip


def ignored_ros2_options(*names: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """ros2cli's shared options, accepted in its forms and kept out of the verb's own arguments; the graph
    reads `--no-daemon` and `--spin-time` from the verb's context (`open_live_graph`), the others mean
    nothing here (said so in --help)."""
    choices = {
        "no_daemon": click.option("--no-daemon", is_flag=True,
                                  help="Ask the ROS 2 graph directly, not its daemon (ROSTOOL_NO_DAEMON=1)."),
        "spin_time": spin_time_option,
        "use_sim_time": click.option("-s", "--use-sim-time", is_flag=True,
                                     help="ROS 2: accepted and ignored (rostool uses the wall clock)."),
        "wall_time": click.option("--wall-time", is_flag=True,
                                  help="Accepted and ignored (rostool always measures wall time)."),
    }  # fmt: skip

    def decorate(func: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            for name in names:
                kwargs.pop(name, None)
            return func(*args, **kwargs)

        for name in reversed(names):
            wrapper = choices[name](wrapper)
        return wrapper

    return decorate
