"""`rostool bag filter`: copy the messages that match into a new bag."""

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


@click.command(name="filter", context_settings=CONTEXT)
@click.argument("paths", nargs=-1, required=True, metavar="IN... OUT")
@topics_option
@time_window_options
@click.option("--filter", "expr", metavar="EXPR", help="Keep messages where EXPR holds (names: m, topic, t).")
@format_option
@writing_options("OUT")
def filter_(
    paths: tuple[str, ...],
    topics: tuple[str, ...],
    start: str | None,
    end: str | None,
    expr: str | None,
    fmt: Any,
    distro: str,
    force: bool,
    jobs: int | None,
) -> None:
    """Copy the messages that match into a new bag (same format as IN unless OUT's name says otherwise).

    EXPR is a safe Python-like expression over the message `m`, its `topic` and its time `t` (seconds):
    field access, indexing, literals, comparisons, and/or/not, len/abs/min/max, string methods.
    Several INs, or a directory of bags, are filtered each on its own, in parallel processes, into the
    folder OUT (OUT/NAME, in the format of each IN unless --format says otherwise).

    \b
    Examples:
      rostool bag filter run.bag fast.bag --filter 'm.linear.x > 1.0' --topics /turtle1/cmd_vel
      rostool bag filter run.bag late.bag --filter 't > 1396293900'
      rostool bag filter rosbag2_dir out --filter 'topic != "/rosout"'
      rostool bag filter fleet/ fleet_no_rosout/ --filter 'topic != "/rosout"' -j 2
    """
    from rostool.bag.convert import Selection, copy_bags
    from rostool.bag.copy_many import CopyJob, is_fleet
    from rostool.bag.message_filter import message_filter

    if len(paths) < 2:
        raise RostoolError("give IN and OUT (e.g. `rostool bag filter in.bag out.bag --topics /odom`)")
    sources, dst = paths[:-1], paths[-1]
    selection = Selection(topic_list(topics), (), start, end)
    if len(sources) > 1 or is_fleet(sources):
        copy_fleet(CopyJob(dst, fmt, selection, expr, distro, force, like_input=True), sources, jobs)
        return
    selection.predicate = message_filter(expr)
    result = copy_bags(sources, dst, fmt, selection, distro=distro, force=force, like_input=True)
    report(result.written, len(result.topics), dst)
