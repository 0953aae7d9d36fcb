"""`rostool bag play` with rosbag play's flags (ROS 1; the ROS 2 form is play_ros2.py)."""

from __future__ import annotations

from collections.abc import Sequence

import click

from rostool.commands._common import match_wait_option
from rostool.commands.bag._options import CONTEXT, distro_option, topic_list, topics_option
from rostool.errors import RostoolError


@click.command(context_settings=CONTEXT)
@click.argument("args", nargs=-1, required=True, metavar="BAG... [FROM:=TO]...")
@click.option("-l", "--loop", is_flag=True, help="Start over at the end, until Ctrl+C.")
@click.option(
    "-r", "--rate", type=click.FloatRange(min=0, min_open=True), default=1.0, show_default=True,
    help="Speed factor (2 = twice as fast).",
)  # fmt: skip
@click.option("-s", "--start", type=click.FloatRange(min=0), default=0.0, metavar="S",
              help="Start S seconds into the bag.")  # fmt: skip
@click.option("-u", "--duration", type=click.FloatRange(min=0, min_open=True), metavar="U",
              help="Play only U seconds of bag time.")  # fmt: skip
@topics_option
@click.option("--clock", is_flag=True, help="Publish the bag time on /clock (rosgraph_msgs/Clock).")
@click.option("--hz", type=click.FloatRange(min=0, min_open=True), metavar="HZ",
              help="/clock messages per second (default 100; ROS 2: 40, as rosbag2).")  # fmt: skip
@click.option("-d", "--delay", type=click.FloatRange(min=0), default=0.2, show_default=True, metavar="S",
              help="Wait S seconds after advertising, so subscribers can connect.")  # fmt: skip
@click.option("--wait-for-subscribers", is_flag=True, help="Wait for a subscriber on every topic first.")
@match_wait_option
@click.option("--pause", is_flag=True, help="Start paused (space resumes; needs a terminal).")
@click.option("-i", "--immediate", is_flag=True, help="Publish all messages without waiting.")
@click.option("-k", "--keep-alive", is_flag=True, help="Keep the (latched) publishers alive at the end.")
@click.option("--remap", multiple=True, metavar="FROM:=TO", help="Publish topic FROM as TO (repeatable).")
@click.option("-p", "--prefix", default="", metavar="PREFIX",
              help="Prefix every topic; --remap then names the prefixed topic, as in rosbag.")  # fmt: skip
@click.option("--skip-empty", type=click.FloatRange(min=0, min_open=True), metavar="SEC",
              help="Skip regions with no message for more than SEC seconds.")  # fmt: skip
@click.option("--pause-topics", multiple=True, metavar="T",
              help="Pause at each message on these bag topics (space resumes; needs a tty).")  # fmt: skip
@click.option("-q", "--quiet", is_flag=True, help="No status line and no messages on stderr.")
@distro_option
@click.pass_context
def play(
    ctx: click.Context,
    args: tuple[str, ...],
    loop: bool,
    rate: float,
    start: float,
    duration: float | None,
    topics: tuple[str, ...],
    clock: bool,
    hz: float | None,
    delay: float,
    wait_for_subscribers: bool,
    match_wait: float,
    pause: bool,
    immediate: bool,
    keep_alive: bool,
    remap: tuple[str, ...],
    prefix: str,
    skip_empty: float | None,
    pause_topics: tuple[str, ...],
    quiet: bool,
    distro: str,
) -> None:
    """Publish the messages of bags into the live graph, on their recorded schedule.

    ROS 1 bags are published byte for byte with their stored types (latched where recorded so). ROS 2
    bags (.mcap, .db3, rosbag2 directories) are converted to ROS 1 (`pkg/msg/T` -> `pkg/T`); topics whose
    type has no ROS 1 equivalent are skipped with a warning. These are rosbag play's flags (ROS 1);
    under ROS 2 (--ros2, ROS_VERSION=2) `bag play` takes ros2 bag play's (see `rostool --ros2 bag play -h`).
    On a terminal, a status line shows the bag time and space pauses/resumes ('s' or the right arrow
    steps while paused, 't' toggles --pause-topics, up/down raise/lower the rate by 10 % as in rosbag2).
    Remappings may also be given as arguments (`/chatter:=/talk`), and with --topics (else
    --pause-topics), further topic names after the bags.

    \b
    Examples:
      rostool bag play run.bag
      rostool bag play -r 2 -s 10 -u 5 run.bag --topics /odom,/tf
      rostool bag play -l --clock run.bag /scan:=/scan_raw
      rostool bag play -p /replay --skip-empty 5 run.bag --pause-topics /goal
      rostool bag play talker.mcap
    """
    from rostool.bag.play import PlayOptions, parse_remaps
    from rostool.commands.bag._playing import PlayRequest, run_play

    paths, remap_args, extra_topics = _play_arguments(args, bool(topics or pause_topics))
    extra_pause = [] if topics else extra_topics
    extra_topics = extra_topics if topics else []
    options = PlayOptions(
        rate=rate,
        start=start,
        duration=duration,
        loop=loop,
        topics=[*topic_list(topics), *extra_topics],
        clock=clock,
        keep_alive=keep_alive,
        wait_for_subscribers=wait_for_subscribers,
        match_wait=match_wait,
        hz=hz or 100.0,  # rosbag's rate; on a ROS 2 graph rosbag2's (ros2_hz)
        delay=delay,
        pause=pause,
        immediate=immediate,
        remap=parse_remaps([*remap_args, *remap]),
        prefix=prefix,
        skip_empty=skip_empty,
        pause_topics=[*topic_list(pause_topics), *extra_pause],
    )
    request = PlayRequest(
        bags=paths,
        distro=distro,
        options=options,
        ros2_hz=hz or 40.0,
        quiet=quiet,
        form="rosbag",
        keyboard=True,
        pause_flags=(("--pause", pause), ("--pause-topics", bool(options.pause_topics))),
        nothing_played_hint="-s/-u and --topics",
    )
    run_play(ctx, request)


def _play_arguments(args: Sequence[str], with_topics: bool) -> tuple[list[str], list[str], list[str]]:
    """Split play's arguments into bags, `FROM:=TO` remappings and (after --topics) topic names."""
    from pathlib import Path

    paths, remaps, topics = [], [], []
    for arg in args:
        if ":=" in arg:
            remaps.append(arg)
        elif with_topics and paths and arg.startswith("/") and not Path(arg).exists() and "." not in arg:
            topics.append(arg)  # `rosbag play x.bag --topics /a /b`: /b ends up here
        else:
            paths.append(arg)
    if not paths:
        raise RostoolError("give at least one bag to play")
    return paths, remaps, topics
