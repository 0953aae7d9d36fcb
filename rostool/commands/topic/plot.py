"""`rostool topic plot`: rqt_plot in the terminal, live numeric fields of topics, ROS 1 and ROS 2."""

from __future__ import annotations

import sys
import time
from collections import deque
from pathlib import Path
from typing import Any

import click

from rostool.commands._common import interfaces_option, live_graph, stdout_is_tty
from rostool.errors import RostoolError
from rostool.output.plot_file import OUTPUT_HELP, output_file_option

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
PATHS_HELP = """\b
FIELD paths (rqt_plot's): /odom/pose/pose/position/x (the longest topic of the graph that prefixes it
is the topic) or /odom.pose.pose.position.x (the topic ends at the first dot: use it for a topic that
has no publisher yet); /scan/ranges[0] for array items; a message field plots every number in it."""
HOME_AND_CLEAR = "\x1b[H\x1b[J"


@click.command(context_settings=CONTEXT)
@click.argument("paths", nargs=-1, required=True, metavar="FIELD...")
@output_file_option("At the end (--duration or Ctrl+C), draw the last window to FILE (.png, .svg, .pdf).")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), metavar="S",
              help="Stop after S seconds (default: at Ctrl+C).")  # fmt: skip
@click.option("--window", type=click.FloatRange(min=0, min_open=True), default=30.0, show_default=True,
              metavar="S", help="Seconds of data shown (and saved with -o).")  # fmt: skip
@click.option("--rate", type=click.FloatRange(min=0.5, max=30), default=4.0, show_default=True, metavar="HZ",
              help="Terminal redraws per second.")  # fmt: skip
@click.option("--csv", "as_csv", is_flag=True,
              help="Print CSV rows as messages come (the default in a pipe).")  # fmt: skip
@click.option("--header-stamp", is_flag=True, help="x = each message's header.stamp instead of receive time.")
@interfaces_option
@click.pass_context
def plot(
    ctx: click.Context, paths: tuple[str, ...], output: Path | None, duration: float | None, window: float,
    rate: float, as_csv: bool, header_stamp: bool, interface_paths: tuple[str, ...],
) -> None:  # fmt: skip
    """Plot numeric fields of live topics as they arrive, like rqt_plot, in the terminal.

    \b
    Examples:
      rostool topic plot /turtle1/pose/x /turtle1/pose/y
      rostool topic plot /odom.twist.twist.linear.x --window 10
      rostool topic plot /imu/linear_acceleration --duration 20 -o accel.png
      rostool --ros2 topic plot /chatter_count/data --csv > counts.csv
    """
    from rostool.graph.inbox import decoded
    from rostool.output.plot_data import Sampler, csv_header, csv_row, parse_spec
    from rostool.output.plot_deps import need
    from rostool.output.plot_draw import check_output

    if output is not None:
        check_output(output)
    interactive = stdout_is_tty() and not as_csv
    as_csv = as_csv or (not interactive and output is None)
    if interactive:
        need("plotille", "plot")  # say which extra to install before subscribing
    arrived: deque[Any] = deque()
    failures: list[str] = []
    with live_graph(ctx, interface_paths) as graph:
        known = {t.name for t in graph.topics()}
        sampler = Sampler([parse_spec(text, known) for text in paths], header_stamp)
        subscriptions = [graph.subscribe(topic, arrived.append, failures.append) for topic in sampler.topics]
        if as_csv:
            sys.stdout.write(csv_header() + "\n")
        started = time.monotonic()
        drawn = 0
        try:
            while duration is None or time.monotonic() - started < duration:
                wait = (
                    1.0 / rate
                    if duration is None
                    else min(1.0 / rate, duration - (time.monotonic() - started))
                )
                time.sleep(max(wait, 0.0))
                if failures:
                    raise RostoolError(failures[0])
                rows = []
                while arrived:
                    received = arrived.popleft()
                    message = decoded(received, received.topic)
                    rows += sampler.add(received.topic, message, received.recv_time_ns)
                if as_csv and rows:
                    sys.stdout.write("".join(csv_row(*row) + "\n" for row in rows))
                    sys.stdout.flush()
                _trim(sampler, window)
                if interactive:
                    drawn = _draw(sampler, header_stamp, window, started, drawn, len(subscriptions))
        except KeyboardInterrupt:
            pass  # Ctrl+C ends the plot like --duration: the last window is kept (and saved with -o)
        finally:
            for subscription in subscriptions:
                subscription.close()
    if output is not None:
        origin = sampler.start_ns()
        if origin is None:
            raise RostoolError(
                f"nothing to save to {output}: no message arrived on {', '.join(sampler.topics)}"
            )
        from rostool.output.plot_file import save_figure

        save_figure(sampler.ordered(), output, origin, header_stamp)


def _trim(sampler: Any, window: float) -> None:
    latest = max((s.times_ns[-1] for s in sampler.series.values() if s.times_ns), default=None)
    if latest is not None:
        for series in sampler.series.values():
            series.trim_before(latest - int(window * 1e9))


def _draw(sampler: Any, header_stamp: bool, window: float, started: float, drawn: int, topics: int) -> int:
    from rostool.output.plot_draw import terminal_text

    out = sys.stdout
    if drawn == 0:
        out.write("\x1b[2J")
    origin = sampler.start_ns()
    count = sum(len(s.values) for s in sampler.series.values())
    status = f"{count} points in the last {window:g} s; Ctrl+C to stop"
    if origin is None:
        text = f"waiting for messages on {', '.join(sampler.topics)} ({time.monotonic() - started:.0f} s)"
    else:
        latest = max(s.times_ns[-1] for s in sampler.series.values() if s.times_ns)
        right = (latest - origin) / 1e9
        text = terminal_text(
            sampler.ordered(), origin, header_stamp, x_span=(max(right - window, 0.0), right)
        )
    out.write(HOME_AND_CLEAR + text + "\n" + status + "\n")
    out.flush()
    return drawn + 1


plot.help = (
    (plot.help or "")
    + "\n\n"
    + PATHS_HELP
    + "\n\n"
    + OUTPUT_HELP.replace("in message order", "as messages arrive")
)
