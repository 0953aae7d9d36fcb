"""`rostool bag burst`: publish N messages of a bag as fast as possible (ros2 bag burst's flags)."""

from __future__ import annotations

from dataclasses import dataclass

import click

from rostool.commands._common import match_wait_option
from rostool.commands.bag._flags import ListCommand, parsed_into
from rostool.commands.bag._options import CONTEXT, topic_list
from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS


@dataclass(frozen=True)
class BurstFlags:
    bag_path: str
    storage: str | None
    read_ahead_queue_size: int
    topics: tuple[str, ...]
    services: tuple[str, ...]
    qos_profile_overrides_path: str | None
    remap: tuple[str, ...]
    storage_config_file: str | None
    start_offset: float
    num_messages: int
    delay: float
    wait_for_subscribers: bool
    match_wait: float
    quiet: bool
    distro: str


@click.command(
    cls=ListCommand,
    list_options=("--topics", "--services", "--remap", "-m"),
    bag_last=True,
    context_settings=CONTEXT,
    short_help="Publish N messages of a bag as fast as possible.",
)
@click.argument("bag_path", metavar="BAG")
@click.option("-s", "--storage", type=click.Choice(["mcap", "sqlite3"]),
              help="Storage of the bag (found from the bag when not given).")  # fmt: skip
@click.option("--read-ahead-queue-size", type=click.IntRange(min=1), default=1000, show_default=True,
              help="Accepted for ros2 bag's sake (messages are read as they are sent).")  # fmt: skip
@click.option("--topics", multiple=True, metavar="TOPIC...", help="Topics to burst (default: all).")
@click.option("--services", multiple=True, metavar="SERVICE...", help="Services whose events to burst.")
@click.option("--qos-profile-overrides-path", type=click.Path(exists=True, dir_okay=False), metavar="FILE",
              help="Accepted: publishers offer the recorded QoS.")  # fmt: skip
@click.option(
    "-m", "--remap", "remap", multiple=True, metavar="OLD:=NEW...", help="Publish topic OLD as NEW."
)
@click.option("--storage-config-file", type=click.Path(exists=True, dir_okay=False), help="Accepted.")
@click.option("--start-offset", type=click.FloatRange(min=0), default=0.0, metavar="S",
              help="Start S seconds into the bag.")  # fmt: skip
@click.option("-n", "--num-messages", type=click.IntRange(min=0), default=0, show_default=True, metavar="N",
              help="Burst N messages (0: every message from the start offset on).")  # fmt: skip
@click.option("-d", "--delay", type=click.FloatRange(min=0), default=0.5, show_default=True, metavar="S",
              help="rostool: wait S seconds after advertising, so subscribers can connect.")  # fmt: skip
@click.option("--wait-for-subscribers", is_flag=True,
              help="rostool: wait for a subscriber on every topic first.")  # fmt: skip
@match_wait_option
@click.option("-q", "--quiet", is_flag=True, help="rostool: no warnings.")
@click.option("--distro", type=click.Choice(sorted(DISTROS)), default=DEFAULT_DISTRO, show_default=True,
              help="rostool: ROS 2 type store for bags that carry no message definitions.")  # fmt: skip
@parsed_into(BurstFlags)
def burst(ctx: click.Context, flags: BurstFlags) -> None:
    """Publish the first N messages of a bag (from --start-offset) as fast as possible, then exit, as
    `ros2 bag burst` does; on a ROS 1 graph too, as `bag play` plays there.

    \b
    Examples:
      rostool bag burst run/ -n 100
      rostool bag burst run.mcap --topics /scan --start-offset 30 -n 10 --wait-for-subscribers
    """
    from rostool.bag.play import PlayOptions, parse_remaps
    from rostool.bag.play_topics import check_storage
    from rostool.bag.qos_overrides import qos_overrides
    from rostool.bag.record_select import services_events
    from rostool.commands.bag._playing import PlayRequest, run_play

    check_storage(flags.bag_path, flags.storage)
    qos_overrides(flags.qos_profile_overrides_path, apply=False)
    topics = [*topic_list(flags.topics), *sorted(services_events(topic_list(flags.services)))]
    options = PlayOptions(
        start=flags.start_offset,
        topics=topics,
        immediate=True,
        remap=parse_remaps(topic_list(flags.remap)),
        delay=flags.delay,
        wait_for_subscribers=flags.wait_for_subscribers,
        match_wait=flags.match_wait,
        max_messages=flags.num_messages or None,
    )
    request = PlayRequest(
        bags=[flags.bag_path],
        distro=flags.distro,
        options=options,
        ros2_hz=40.0,
        quiet=flags.quiet,
        form="rosbag",
        keyboard=False,
        pause_flags=(),
        nothing_played_hint="--start-offset and --topics",
    )
    if not topics and flags.topics:
        raise RostoolError("--topics: give at least one topic name")
    result = run_play(ctx, request)
    if not flags.quiet and result.published:
        click.echo(f"Burst {result.published} messages.", err=True)
