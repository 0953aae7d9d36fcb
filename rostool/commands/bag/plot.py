"""`rostool bag plot`: numeric fields of a bag's messages against time (rqt_plot's paths), as a file, a
terminal plot or CSV."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from rostool.commands._common import stdout_is_tty
from rostool.commands.bag._options import CONTEXT, TIME_HELP
from rostool.errors import RostoolError
from rostool.output.plot_file import OUTPUT_HELP, output_file_option

PATHS_HELP = """\b
FIELD paths (rqt_plot's): /odom/pose/pose/position/x (the longest topic of the bag that prefixes it is
the topic) or /odom.pose.pose.position.x (the topic ends at the first dot); /scan/ranges[0] or
/scan/ranges/0 for array items. A message or array field plots every number in it (/turtle1/pose)."""


@click.command(context_settings=CONTEXT)
@click.argument("bag_path", metavar="BAG")
@click.argument("paths", nargs=-1, required=True, metavar="FIELD...")
@output_file_option("Draw to FILE (.png, .svg, .pdf).")
@click.option("--csv", "as_csv", is_flag=True, help="Print CSV (the default in a pipe).")
@click.option("--start", metavar="S", help=f"First message time: {TIME_HELP}.")
@click.option("--end", metavar="S", help=f"Last message time: {TIME_HELP}.")
@click.option("--header-stamp", is_flag=True, help="x = each message's header.stamp instead of bag time.")
@click.option("--title", default="", help="A title for the figure.")
@click.option(
    "--distro",
    default=None,
    metavar="DISTRO",
    help="ROS 2 type store for bags that carry no message definitions (default: rostool's).",
)
def plot(
    bag_path: str, paths: tuple[str, ...], output: Path | None, as_csv: bool, start: str | None,
    end: str | None, header_stamp: bool, title: str, distro: str | None,
) -> None:  # fmt: skip
    """Plot numeric fields of a bag's messages against time, as rqt_plot does for live topics.

    \b
    Examples:
      rostool bag plot run.bag /turtle1/cmd_vel/linear/x /turtle1/cmd_vel/angular/z
      rostool bag plot run.bag /odom.pose.pose.position.x -o x.svg --start +5 --end +20
      rostool bag plot run.bag /turtle1/pose -o pose.png
      rostool bag plot run.bag /imu/linear_acceleration/z --header-stamp --csv > accel.csv
    """
    from rostool.bag.convert import parse_time
    from rostool.bag.reader import BagReader
    from rostool.interfaces.typestores import DEFAULT_DISTRO
    from rostool.output.plot_data import Sampler, csv_header, csv_row, parse_spec
    from rostool.output.plot_draw import check_output

    if output is not None:
        if as_csv:
            raise RostoolError("choose one of -o and --csv")
        check_output(output)
    as_csv = as_csv or (output is None and not stdout_is_tty())
    with BagReader([bag_path], distro or DEFAULT_DISTRO) as reader:
        specs = [parse_spec(text, reader.topics) for text in paths]
        unknown = next((s for s in specs if s.topic not in reader.topics), None)
        if unknown is not None:
            raise RostoolError(
                f"topic {unknown.topic} is not in the bag (topics: {', '.join(reader.topics)})"
            )
        sampler = Sampler(specs, header_stamp)
        first, last = parse_time(start, reader.start_ns, "start"), parse_time(end, reader.start_ns, "end")
        write = sys.stdout.write
        if as_csv:
            write(csv_header() + "\n")
        for conn, timestamp, data in reader.messages(reader.select(sampler.topics), first, last):
            points = sampler.add(conn.topic, reader.deserialize(data, conn), timestamp)
            if as_csv:
                write("".join(csv_row(*point) + "\n" for point in points))
        origin = sampler.start_ns()
    if as_csv:
        sys.stdout.flush()
        return
    if origin is None:
        raise RostoolError("no message of these topics in the bag (or between --start and --end)")
    series = sampler.ordered()
    if output is not None:
        from rostool.output.plot_file import save_figure

        save_figure(series, output, origin, header_stamp, title)
    else:
        from rostool.output.plot_draw import terminal_text

        click.echo(terminal_text(series, origin, header_stamp))


plot.help = (plot.help or "") + "\n\n" + PATHS_HELP + "\n\n" + OUTPUT_HELP
