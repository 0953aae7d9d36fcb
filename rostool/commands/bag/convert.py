"""`rostool bag convert`: between ROS 1 .bag, .mcap, .db3 and rosbag2 directories."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands.bag._copying import (
    copy_fleet,
    format_option,
    report,
    time_window_options,
    writing_options,
)
from rostool.commands.bag._options import CONTEXT, topic_list, topics_option
from rostool.errors import RostoolError


@click.command(context_settings=CONTEXT)
@click.argument("paths", nargs=-1, required=True, metavar="SRC... DST")
@format_option
@topics_option
@click.option("--exclude-topics", multiple=True, metavar="T", help="Leave these topics out.")
@time_window_options
@writing_options("DST")
def convert(
    paths: tuple[str, ...],
    fmt: Any,
    topics: tuple[str, ...],
    exclude_topics: tuple[str, ...],
    start: str | None,
    end: str | None,
    distro: str,
    force: bool,
    jobs: int | None,
) -> None:
    """Convert bags between ROS 1 .bag, .mcap, .db3 and rosbag2 directories.

    DST ending in .bag is a ROS 1 bag, in .mcap/.db3 a single self-describing storage file, anything
    else a rosbag2 directory (mcap storage unless --format db3). Message types and bytes are converted
    between ROS 1 and ROS 2 (tf/tfMessage becomes tf2_msgs/msg/TFMessage; other types keep their name
    and carry their definition). DST is written under a temporary name and appears only when complete.
    Several SRC bags are merged into DST; a SRC that is a directory of bags converts each bag on its
    own, in parallel processes, into DST/NAME.FORMAT (a rosbag2 directory DST/NAME without --format).

    \b
    Examples:
      rostool bag convert run.bag run.mcap
      rostool bag convert rosbag2_dir/ run.bag --topics /tf,/odom
      rostool bag convert part1.bag part2.bag merged --format db3 --start +10 --end +20
      rostool bag convert fleet/ fleet_mcap/ --format mcap -j 2
    """
    from rostool.bag.convert import Selection, copy_bags
    from rostool.bag.copy_many import CopyJob, is_fleet

    if len(paths) < 2:
        raise RostoolError("give at least one SRC and a DST (e.g. `rostool bag convert in.bag out.mcap`)")
    selection = Selection(topic_list(topics), topic_list(exclude_topics), start, end)
    sources = paths[:-1]
    if is_fleet(sources):
        job = CopyJob(paths[-1], fmt, selection, None, distro, force, like_input=False)
        copy_fleet(job, sources, jobs)
        return
    result = copy_bags(sources, paths[-1], fmt, selection, distro=distro, force=force)
    report(result.written, len(result.topics), paths[-1])
