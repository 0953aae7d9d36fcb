"""`rostool action send-goal` (and ros2's send_goal): send a goal, follow it to its result."""

from __future__ import annotations

import re
import sys

import click

from rostool.commands._common import ignored_ros2_options, interfaces_option, json_option, live_graph

_TYPE_NAME = re.compile(r"[A-Za-z][\w]*/(action/)?[A-Za-z]\w*\Z")


@click.command("send-goal", context_settings={"ignore_unknown_options": True})
@click.argument("name", metavar="ACTION")
@click.argument("values", nargs=-1, metavar="[TYPE] GOAL...")
@click.option(
    "-f", "--feedback", "show_feedback", is_flag=True, help="Print each feedback message as it arrives."
)
@click.option("--stdin", "from_stdin", is_flag=True, help="Read the goal (YAML) from standard input.")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    help="Cancel the goal and exit 1 when it has no result after S seconds.",
)
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def send_goal(
    ctx: click.Context, name: str, values: tuple[str, ...], show_feedback: bool, from_stdin: bool,
    timeout: float | None, interface_paths: tuple[str, ...], as_json: bool,
) -> None:  # fmt: skip
    """Send a goal and wait for its result; Ctrl+C (or --timeout) cancels the goal first.

    GOAL is one YAML mapping, or the goal's field values in order. TYPE (pkg/Type) may be left out when
    the server is running: it is read from ACTION/goal. Exit status: 0 when the goal SUCCEEDED, 1 for any
    other final status or a timeout, 130 on Ctrl+C.

    \b
    Examples:
      rostool action send-goal /navigate_2d_action "{point: {x: 1.0, y: 2.0, z: 0.0}}" --feedback
      rostool action send-goal /fibonacci actionlib_tutorials/Fibonacci "{order: 5}" --timeout 30
      rostool --ros2 action send-goal /count robo_msgs/action/Count "{count: 3}" --interfaces ~/ros2_ws
    """
    from rostool.interfaces.values import message_args
    from rostool.output.goal_text import GoalText, Ros2GoalText

    if from_stdin:
        values = (*values, sys.stdin.read())
    if not values:
        raise click.UsageError("Missing argument '[TYPE] GOAL...' (or give the goal on stdin with --stdin).")
    type_name, goal_values = _split_goal_args(values)
    goal = message_args(goal_values)
    with live_graph(ctx, interface_paths) as graph:
        watcher = (GoalText if graph.style == "ros1" else Ros2GoalText)(as_json, show_feedback)
        outcome = graph.send_goal(name, type_name, goal, timeout, watcher)
    if not outcome.succeeded:
        ctx.exit(1)


def _split_goal_args(values: tuple[str, ...]) -> tuple[str | None, tuple[str, ...]]:
    """[TYPE] GOAL...: a first value spelled pkg/Type (never valid goal YAML) is the type."""
    if len(values) >= 2 and _TYPE_NAME.match(values[0]):
        return values[0], values[1:]
    return None, values
