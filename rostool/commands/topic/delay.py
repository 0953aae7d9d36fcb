"""`rostool topic delay`: the delay between a message's header.stamp and its arrival (rostopic delay)."""

from __future__ import annotations

import time

import click

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.errors import RostoolError


@click.command("delay")
@click.argument("name")
@click.option("-w", "--window", type=click.IntRange(min=1), help="Average over the last N messages only.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def delay(ctx: click.Context, name: str, window: int | None, duration: float | None) -> None:
    """Measure the delay between a message's header.stamp and its arrival.

    \b
    Example:
      rostool topic delay /scan
    """
    from rostool.graph.inbox import Inbox
    from rostool.graph.rates import RunningStats
    from rostool.output.rate_text import delay_text

    stats = RunningStats(window)
    with live_graph(ctx) as graph:
        inbox = Inbox(graph, name)
        if graph.style == "ros1":
            click.echo(f"subscribed to [{name}]")
        started = next_report = time.monotonic()
        for received in inbox.messages():
            stamp = getattr(getattr(received.decode(), "header", None), "stamp", None)
            if stamp is None:
                raise RostoolError(f"messages on {name} have no header.stamp; delay needs one")
            stats.add(received.recv_time_ns / 1e9 - (stamp.sec + stamp.nanosec / 1e9))
            now = time.monotonic()
            if now >= next_report + 1.0:
                next_report = now
                s = stats.summary()
                if s is not None:
                    click.echo(delay_text(s))
            if duration is not None and now - started >= duration:
                break
