"""`rostool console`: echo nodes' log messages, and list, get and set their logger levels (rosconsole's and
rqt_console's jobs, for ROS 1 and ROS 2)."""

from __future__ import annotations

import json
import threading

import click
from click.shell_completion import CompletionItem

from rostool.commands._common import json_option, live_graph, print_json
from rostool.errors import RostoolError
from rostool.graph import console as con

LEVEL_COLOURS = {"debug": "bright_green", "info": None, "warn": "bright_yellow", "error": "bright_red",
                 "fatal": "bright_magenta"}  # fmt: skip


@click.group()
def console() -> None:
    """Read nodes' log messages and change their logger levels (like rosconsole and rqt_console; ROS 1 and
    ROS 2).

    \b
    Examples:
      rostool console echo                       # every node's log lines, as they come
      rostool console echo --level warn --node /talker
      rostool console list /talker               # its loggers
      rostool console get /talker                # info
      rostool console set /talker debug          # its own logger; or: set /talker LOGGER debug

    ROS 2 nodes serve their logger levels only when created with enable_logger_service=True.
    """


def render(entry: con.LogEntry) -> str:
    """`[LEVEL] [seconds.nanoseconds] [name]: message`, as ROS 2 prints its console lines."""
    seconds, nanoseconds = divmod(entry.stamp_ns, 1_000_000_000)
    level = f"[{entry.level.upper()}]"
    colour = LEVEL_COLOURS.get(entry.level)
    if colour:
        level = click.style(level, fg=colour, bold=True if entry.level == "fatal" else None)
    return f"{level} [{seconds}.{nanoseconds:09d}] [{entry.name}]: {entry.msg}"


@console.command("echo")
@click.option("-l", "--level", "min_level", default="debug", help="Only messages at this level or above.",
              type=click.Choice(con.LEVELS, case_sensitive=False))  # fmt: skip
@click.option(
    "--node", "node", metavar="NODE", help="Only messages of NODE (ROS 2: its logger and children)."
)
@click.option(
    "--topic", metavar="TOPIC", help="Read another topic (default: ROS 2 /rosout, ROS 1 /rosout_agg)."
)
@click.option("-n", "--count", type=click.IntRange(min=1), help="Stop after N messages.")
@json_option
@click.pass_context
def echo(
    ctx: click.Context, min_level: str, node: str | None, topic: str | None, count: int | None, as_json: bool
) -> None:
    """Print nodes' log messages as they are published: time, level, node (ROS 2: logger), message.
    Levels are coloured on a terminal; --json prints one JSON object a line. ROS 2 nodes keep their lines
    of the last 10 s for newcomers, so echo starts with those.

    \b
    Examples:
      rostool console echo
      rostool console echo --level warn --node /talker
      rostool console echo --json -n 10
    """
    level = con.level_name(min_level)
    printed = 0
    done = threading.Event()
    lock = threading.Lock()
    with live_graph(ctx) as graph:
        keep = con.entry_filter(graph.style, level, node)

        def on_entry(entry: con.LogEntry) -> None:
            nonlocal printed
            if not keep(entry):
                return
            with lock:
                if done.is_set():
                    return
                click.echo(json.dumps(entry.as_dict()) if as_json else render(entry))
                printed += 1
                if count is not None and printed >= count:
                    done.set()

        subscription = con.follow_log(graph, on_entry, topic)
        try:
            done.wait()
        finally:
            subscription.close()


@console.command("list")
@click.argument("node", metavar="NODE")
@json_option
@click.pass_context
def list_loggers(ctx: click.Context, node: str, as_json: bool) -> None:
    """List NODE's loggers (ROS 2: the node's own logger; its services cannot list others).

    \b
    Examples:
      rostool console list /talker
      rostool console list /talker --json     # with their levels
    """
    with live_graph(ctx) as graph:
        levels = con.logger_levels(graph, node)
    if as_json:
        print_json([{"name": name, "level": level} for name, level in levels.items()])
        return
    for name in levels:
        click.echo(name)


@console.command("get")
@click.argument("node", metavar="NODE")
@click.argument("logger", metavar="[LOGGER]", required=False)
@click.pass_context
def get(ctx: click.Context, node: str, logger: str | None) -> None:
    """Print the level of one of NODE's loggers (default: the one its own messages use).

    \b
    Examples:
      rostool console get /talker                 # info
      rostool console get /talker rospy.topics    # ROS 1: any logger `console list` shows
    """
    with live_graph(ctx) as graph:
        if graph.style == "ros1":
            levels = con.logger_levels(graph, node)
            logger = logger or con.default_logger(graph, node, levels)
        else:
            logger = logger or con.default_logger(graph, node)
            levels = con.logger_levels(graph, node, [logger])
    if logger not in levels:
        raise RostoolError(f"node {node} has no logger {logger} (see `rostool console list {node}`)")
    click.echo(levels[logger])


def _complete_level(_ctx: click.Context, _param: click.Parameter, incomplete: str) -> list[CompletionItem]:
    return [CompletionItem(level) for level in con.LEVELS if level.startswith(incomplete.lower())]


@console.command("set")
@click.argument("node", metavar="NODE")
@click.argument("words", metavar="[LOGGER] LEVEL", nargs=-1, required=True, shell_complete=_complete_level)
@click.pass_context
def set_level(ctx: click.Context, node: str, words: tuple[str, ...]) -> None:
    """Set the level of one of NODE's loggers (default: the one its own messages use) to LEVEL (debug,
    info, warn, error, fatal).

    \b
    Examples:
      rostool console set /talker debug
      rostool console set /talker rosout warn     # ROS 1: rospy's logger by name
    """
    if len(words) > 2:
        raise RostoolError("console set takes NODE [LOGGER] LEVEL: too many values")
    level = con.level_name(words[-1])
    with live_graph(ctx) as graph:
        logger = words[0] if len(words) == 2 else con.default_logger(graph, node)
        con.set_logger_level(graph, node, logger, level)
