"""Root click group: global options and lazy loading of the command groups.

Command modules are imported only when their group is invoked, so `rostool --help`
never loads the ROS machinery.
"""

from __future__ import annotations

import errno
import importlib
import os
import sys

import click

from rostool import __version__
from rostool.errors import RostoolError

# name -> (module, attribute, one-line help shown by `rostool --help` without importing it)
COMMANDS: dict[str, tuple[str, str, str]] = {
    "core": ("rostool.commands.core", "core", "Run an embedded ROS 1 master and parameter server."),
    "node": ("rostool.commands.node", "node", "List, inspect, ping and kill nodes."),
    "topic": ("rostool.commands.topic", "topic", "List, echo, publish and measure topics."),
    "param": ("rostool.commands.param", "param", "Get, set, dump and load parameters."),
    "msg": ("rostool.commands.msg", "msg", "Show message types and their md5sums."),
    "service": ("rostool.commands.service", "service", "List, inspect and call services."),
    "srv": ("rostool.commands.srv", "srv", "Show service types and their md5sums."),
    "interface": ("rostool.commands.interface", "interface", "Show and list ROS 2 interface types."),
    "action": ("rostool.commands.action", "action", "List actions, send goals, follow feedback, cancel."),
    "bag": ("rostool.commands.bag", "bag", "Inspect, play, record and convert bags (.bag, .db3, .mcap)."),
    "graph": ("rostool.commands.graph", "graph", "Show the node/topic graph as text, DOT, JSON, SVG or PNG."),
    "daemon": (
        "rostool.commands.daemon",
        "daemon",
        "Start, stop and query the ROS 2 graph daemon that makes listings answer at once.",
    ),
    "lifecycle": ("rostool.commands.lifecycle", "lifecycle", "Get and change ROS 2 lifecycle nodes' states."),
    "console": (
        "rostool.commands.console",
        "console",
        "Follow log output and get or set nodes' logger levels.",
    ),
    "doctor": (
        "rostool.commands.doctor",
        "doctor",
        "Show the ROS version, ROS 2 backend, RMW, distro and domain in use, and check the network.",
    ),
    "multicast": (
        "rostool.commands.multicast",
        "multicast",
        "Check that UDP multicast passes between machines (ros2 multicast).",
    ),
    "cheatsheet": (
        "rostool.commands.cheatsheet",
        "cheatsheet",
        "Search the ROS 1 / ROS 2 / rostool command reference.",
    ),
}


class LazyGroup(click.Group):
    """A group whose subcommands are imported on first use."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        available = [name for name, spec in COMMANDS.items() if _module_exists(spec[0])]
        return sorted(available)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        spec = COMMANDS.get(cmd_name)
        if spec is None or not _module_exists(spec[0]):
            return None
        from rostool.commands._common import attach_completion

        module = importlib.import_module(spec[0])
        command: click.Command = getattr(module, spec[1])
        return attach_completion(command)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, COMMANDS[name][2]) for name in self.list_commands(ctx)]
        if not rows:
            return
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except RostoolError as err:
            click.echo(f"rostool: {err}", err=True)
            ctx.exit(err.exit_code)
        except KeyboardInterrupt:
            ctx.exit(130)
        except BrokenPipeError:
            # A closed pipe (e.g. `| head`) is a normal end; stop quietly.
            _silence_stdout()
            ctx.exit(0)
        except OSError as err:
            if err.errno != errno.ENOSPC:
                raise
            # Writers close what they wrote on the way out; say what happened in one line.
            where = f" writing {err.filename}" if err.filename else ""
            click.echo(f"rostool: the disk is full{where}: free some space (or write elsewhere) and retry",
                       err=True)  # fmt: skip
            ctx.exit(1)
        return None


def _module_exists(module: str) -> bool:
    from importlib.util import find_spec

    return find_spec(module) is not None


def _silence_stdout() -> None:
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


@click.group(
    cls=LazyGroup,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.option("--ros1", "ros_version", flag_value=1, help="Talk to a ROS 1 graph.")
@click.option("--ros2", "ros_version", flag_value=2, help="Talk to a ROS 2 graph.")
@click.option(
    "--ros2-backend",
    type=click.Choice(["auto", "rclpy", "dds"]),
    help="ROS 2 through rclpy (your client library and RMW) or rostool's own DDS; auto: rclpy when it "
    "imports (env ROSTOOL_ROS2_BACKEND). `rostool doctor` shows the choice.",
)
@click.version_option(__version__, prog_name="rostool")
@click.pass_context
def root(ctx: click.Context, ros_version: int | None, ros2_backend: str | None) -> None:
    """rostool: rosnode, rostopic, rosparam, rosbag, rosservice and actionlib tools in one.

    Works with ROS 1 and ROS 2 graphs and with .bag, .db3 and .mcap bags, without a ROS installation.
    Without --ros1/--ros2 the version comes from ROS_VERSION, else ROS 1 when ROS_MASTER_URI is set
    or a master answers on localhost:11311, else ROS 2.

    \b
    Examples:
      rostool topic list
      rostool topic echo /hello_world -n 3
      rostool param get /rosdistro
      rostool bag info test.bag
    """
    from rostool.commands._common import Settings

    ctx.obj = Settings(ros_version=ros_version, ros2_backend=ros2_backend)


def main() -> None:
    try:
        root.main(prog_name="rostool")
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as err:
        if _interrupted(err):  # Ctrl+C inside an import can surface wrapped (e.g. by __set_name__)
            sys.exit(130)
        # A bug of ours, not the user's: still one line, with a way to see the details.
        if os.environ.get("ROSTOOL_DEBUG"):
            raise
        click.echo(
            f"rostool: internal error: {type(err).__name__}: {err} (set ROSTOOL_DEBUG=1 for details)",
            err=True,
        )
        sys.exit(70)


def _interrupted(err: BaseException) -> bool:
    seen: set[int] = set()
    current: BaseException | None = err
    while current is not None and id(current) not in seen:
        if isinstance(current, KeyboardInterrupt):
            return True
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return False
