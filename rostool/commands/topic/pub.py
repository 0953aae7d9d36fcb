"""`rostool topic pub`: rostopic pub's forms under ROS 1 (once and latched, or at -r), ros2 topic pub's under
ROS 2 (1 Hz until -1/-t/Ctrl+C, printing each message)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import click

from rostool.commands._common import (
    ignored_ros2_options,
    interfaces_option,
    match_wait_option,
    open_live_graph,
    ros_version,
    warner,
)
from rostool.commands._qos import topic_qos_options
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest


@click.command("pub")
@click.argument("name")
@click.argument("type_name", metavar="TYPE")
@click.argument("values", nargs=-1)
@click.option("-r", "--rate", type=click.FloatRange(min=0, min_open=True),
              help="Publish repeatedly at HZ (ROS 2: 1 Hz when not given).")  # fmt: skip
@click.option("-1", "--once", is_flag=True, help="Publish once, then exit (ROS 1: stay latched 3 s first; "
              "ROS 2: after --keep-alive).")  # fmt: skip
@click.option("-l", "--latch", is_flag=True, help="Latch the last message for late subscribers.")
@click.option("-n", "n_value", metavar="N|NAME", help="ROS 1: with -r, stop after N messages. ROS 2: "
              "--node-name (a number still means N messages).")  # fmt: skip
@click.option("--count", type=click.IntRange(min=1), help="With -r: stop after N messages.")
@click.option("--node-name", help="ROS 2: the name of the publishing node (default: rostool).")
@click.option("-t", "--times", type=click.IntRange(min=1),
              help="ROS 2: publish N times at --rate, then exit.")  # fmt: skip
@click.option("-w", "--wait-matching-subscriptions", "wait_matching", type=click.IntRange(min=0),
              help="ROS 2: first wait for N matching subscriptions (default: the subscribers discovery "
              "shows, at most 3 s, with -1/-t).")  # fmt: skip
@click.option("-m", "--max-wait-time-secs", "max_wait", type=click.FloatRange(min=0),
              help="ROS 2: wait at most S seconds for -w's subscriptions.")  # fmt: skip
@click.option("--keep-alive", type=click.FloatRange(min=0), default=0.1, show_default=True,
              help="ROS 2: stay up S seconds after the last message.")  # fmt: skip
@click.option("-p", "--print", "print_nth", type=click.IntRange(min=0), default=1, show_default=True,
              help="ROS 2: print every N-th message published (0: none).")  # fmt: skip
@click.option("--stdin", "from_stdin", is_flag=True, help="Read the message (YAML) from standard input.")
@click.option("-f", "--file", "file", type=click.Path(exists=True, dir_okay=False),
              help="YAML messages separated by ---.")  # fmt: skip
@click.option("-q", "--quiet", is_flag=True, help="Print nothing.")
@match_wait_option
@interfaces_option
@ignored_ros2_options("spin_time", "use_sim_time")
@click.pass_context
@topic_qos_options
def pub(
    ctx: click.Context, name: str, type_name: str, values: tuple[str, ...], rate: float | None, once: bool,
    latch: bool, n_value: str | None, count: int | None, node_name: str | None, times: int | None,
    wait_matching: int | None, max_wait: float | None, keep_alive: float, print_nth: int, from_stdin: bool,
    file: str | None, quiet: bool, match_wait: float, interface_paths: tuple[str, ...], qos: QosRequest,
) -> None:  # fmt: skip
    """Publish a message given as YAML (missing fields get defaults).

    VALUES is one YAML mapping or the field values in order, as rostopic pub takes them. TYPE may be
    a custom type whose .msg file is in a source tree (--interfaces, ROS_PACKAGE_PATH, the workspace
    around the current directory): no build needed. `stamp: now` sets a time to now; under ROS 2
    `header: auto` sets the header's stamp to now, as ros2 topic pub does.

    Under ROS 1 without -r the message is published once and latched (rostopic pub); under ROS 2 it is
    published at 1 Hz until -1/-t/Ctrl+C (ros2 topic pub), printing `publishing #N: ...`. The first
    message waits until every subscriber the graph shows has matched (at most --match-wait s).

    \b
    Examples:
      rostool topic pub /chatter std_msgs/String "data: hi" -1
      rostool topic pub /cmd_vel geometry_msgs/Twist "{linear: {x: 0.5}}" -r 10
      rostool topic pub /point geometry_msgs/Point 1.0 2.0 3.0 -1
      rostool topic pub /status book_msgs/Status "{level: 2}" --interfaces ~/catkin_ws -1
      rostool --ros2 topic pub -t 5 -w 1 /chatter std_msgs/msg/String "{data: hi}"
    """
    from rostool.graph import select_ros_version
    from rostool.graph.publishing import Ros2Publication, publish_loop, publish_ros2

    if n_value is not None:
        if n_value.isdigit() and int(n_value) >= 1:
            count = int(n_value)
        elif select_ros_version(ros_version(ctx)) == 2:
            node_name = n_value
        else:
            raise RostoolError(f"-n takes a number of messages (at least 1), not {n_value!r}")
    if from_stdin:
        values = (sys.stdin.read(),)
    graph = open_live_graph(ctx, interface_paths, node_name or "rostool")
    try:
        graph.use_qos(qos)
        say: Callable[[str], None] = (lambda _t: None) if quiet else click.echo
        warn = warner(quiet)
        if graph.style == "ros2" and not latch and not file:
            total = 1 if once else times if times is not None else count
            wait_matching = _ros2_wait(wait_matching, max_wait, once or times is not None)
            plan = Ros2Publication(rate or 1.0, total, wait_matching, max_wait, keep_alive)
            printer = _printer(0 if quiet else print_nth)
            publish_ros2(graph, name, type_name, values, plan, click.echo, printer, match_wait, warn)
            return
        publish_loop(
            graph, name, type_name, values, rate=rate, once=once, latch=latch, count=count or times,
            file=file, say=say, match_wait=match_wait, warn=warn,
        )  # fmt: skip
    finally:
        graph.close()


def _ros2_wait(wait_matching: int | None, max_wait: float | None, counted: bool) -> int | None:
    """ros2 topic pub's -w with --max-wait-time-secs: it bounds a wait for subscriptions, so it needs one
    (-w N, or -1/-t, which then wait for one as ros2's do). rostool's -m 0 (ros2 takes only S > 0): no
    wait."""
    if not max_wait:
        return wait_matching
    if wait_matching == 0 or (wait_matching is None and not counted):
        raise RostoolError(
            "--max-wait-time-secs option is only effective with --wait-matching-subscriptions, --once or "
            "--times"
        )
    return 1 if wait_matching is None else wait_matching


def _printer(print_nth: int) -> Callable[[int, Any], None] | None:
    """ros2 topic pub's `publishing #N: <repr>` for every N-th message (-p; 0: none)."""
    from rostool.output.repr_text import message_repr

    def on_sent(sent: int, message: Any) -> None:
        if sent % print_nth == 0:
            click.echo(f"publishing #{sent}: {message_repr(message)}\n")

    return on_sent if print_nth else None
