"""`rostool bag play` with ros2 bag play's flags (under ROS 2: --ros2, ROS_VERSION=2 or a detected ROS 2
graph). The letters mean what they mean to `ros2 bag` (Jazzy/Kilted): `-p` starts paused, `-s` names the
storage, `--clock [HZ]`, `--topics a b`, `-m/--remap old:=new`."""

from __future__ import annotations

from dataclasses import dataclass

import click

from rostool.commands._common import match_wait_option
from rostool.commands.bag._flags import ListCommand, parsed_into
from rostool.commands.bag._options import CONTEXT, topic_list
from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS


@dataclass(frozen=True)
class PlayFlags:
    bag_path: str | None
    storage: str | None
    read_ahead_queue_size: int
    rate: float
    topics: tuple[str, ...]
    services: tuple[str, ...]
    regex: str
    exclude_regex: str
    exclude_topics: tuple[str, ...]
    exclude_services: tuple[str, ...]
    qos_profile_overrides_path: str | None
    loop: bool
    remap: tuple[str, ...]
    storage_config_file: str | None
    clock: float | None
    clock_topics: tuple[str, ...]
    clock_topics_all: bool
    delay: float
    playback_duration: float | None
    playback_until_sec: float | None
    playback_until_nsec: int | None
    disable_keyboard_controls: bool
    start_paused: bool
    start_offset: float
    wait_for_all_acked: int
    disable_loan_message: bool
    log_level: str
    inputs: tuple[str, ...]
    quiet: bool
    duration: float | None
    hz: float | None
    immediate: bool
    keep_alive: bool
    wait_for_subscribers: bool
    match_wait: float
    prefix: str
    skip_empty: float | None
    distro: str


PLAY_LISTS = (
    "--topics", "--services", "--exclude-topics", "--exclude-services", "--remap", "-m", "--clock-topics",
)  # fmt: skip


@click.command(
    cls=ListCommand,
    list_options=PLAY_LISTS,
    optional_values={"--clock": "40"},
    bag_last=True,
    context_settings=CONTEXT,
    short_help="Play back ROS 2 data from a bag.",
)
@click.argument("bag_path", metavar="BAG", required=False)
@click.option("-s", "--storage", type=click.Choice(["mcap", "sqlite3"]),
              help="Storage of the bag (found from the bag when not given).")  # fmt: skip
@click.option("--read-ahead-queue-size", type=click.IntRange(min=1), default=1000, show_default=True,
              help="Accepted for ros2 bag's sake (messages are read as they are due).")  # fmt: skip
@click.option("-r", "--rate", type=click.FloatRange(min=0, min_open=True), default=1.0, show_default=True,
              help="Rate at which to play back messages (> 0).")  # fmt: skip
@click.option("--topics", multiple=True, metavar="TOPIC...", help="Topics to replay (default: all).")
@click.option("--services", multiple=True, metavar="SERVICE...", help="Services whose events to replay.")
@click.option("-e", "--regex", default="", metavar="RE", help="Replay only topics whose name contains RE.")
@click.option(
    "-x", "--exclude-regex", default="", metavar="RE", help="Leave out topics whose name contains RE."
)
@click.option("--exclude-topics", multiple=True, metavar="TOPIC...", help="Topics not to replay.")
@click.option(
    "--exclude-services", multiple=True, metavar="SERVICE...", help="Services whose events not to replay."
)
@click.option("--qos-profile-overrides-path", type=click.Path(exists=True, dir_okay=False), metavar="FILE",
              help="Accepted: publishers offer the recorded QoS.")  # fmt: skip
@click.option("-l", "--loop", is_flag=True, help="Play the bag again and again until Ctrl+C.")
@click.option(
    "-m", "--remap", "remap", multiple=True, metavar="OLD:=NEW...", help="Publish topic OLD as NEW."
)
@click.option("--storage-config-file", type=click.Path(exists=True, dir_okay=False), help="Accepted.")
@click.option("--clock", type=click.FloatRange(min=0, min_open=True), metavar="[HZ]",
              help="Publish /clock at HZ (alone: 40), as a ROS time source.")  # fmt: skip
@click.option(
    "--clock-topics",
    multiple=True,
    metavar="TOPIC...",
    help="Publish the time of each message on these topics to /clock.",
)
@click.option("--clock-topics-all", is_flag=True, help="Publish the time of every message to /clock.")
@click.option("-d", "--delay", type=click.FloatRange(min=0), default=0.0, metavar="S",
              help="Sleep S seconds before playing.")  # fmt: skip
@click.option("--playback-duration", type=click.FloatRange(min=0, min_open=True), metavar="S",
              help="Play S seconds of the bag.")  # fmt: skip
@click.option("--playback-until-sec", type=float, metavar="T",
              help="Play until bag time T (seconds since the epoch).")  # fmt: skip
@click.option("--playback-until-nsec", type=int, metavar="T",
              help="Play until bag time T (nanoseconds since the epoch).")  # fmt: skip
@click.option("--disable-keyboard-controls", is_flag=True, help="Read no keys from the terminal.")
@click.option("-p", "--start-paused", is_flag=True,
              help="Start paused (space or the /rosbag2_player/resume service resumes).")  # fmt: skip
@click.option("--start-offset", type=click.FloatRange(min=0), default=0.0, metavar="S",
              help="Start S seconds into the bag.")  # fmt: skip
@click.option("--wait-for-all-acked", type=click.IntRange(min=-1), default=-1, metavar="MS", help="Accepted.")
@click.option("--disable-loan-message", is_flag=True, help="Accepted.")
@click.option("--log-level", type=click.Choice(["debug", "info", "warn", "error", "fatal"]), default="info",
              help="Accepted for ros2 bag's sake.")  # fmt: skip
@click.option(
    "-i", "--input", "inputs", multiple=True, metavar="BAG", help="Also play this bag (repeatable)."
)
@click.option("-q", "--quiet", is_flag=True, help="rostool: no status line and no warnings.")
@click.option("-u", "--duration", type=click.FloatRange(min=0, min_open=True), metavar="S",
              help="rostool: like --playback-duration.")  # fmt: skip
@click.option("--hz", type=click.FloatRange(min=0, min_open=True), metavar="HZ",
              help="rostool: /clock rate with --clock given alone.")  # fmt: skip
@click.option("--immediate", is_flag=True, help="rostool: publish all messages without waiting.")
@click.option("-k", "--keep-alive", is_flag=True, help="rostool: keep the publishers alive at the end.")
@match_wait_option
@click.option("--wait-for-subscribers", is_flag=True, help="rostool: wait for a subscriber on every topic.")
@click.option("--prefix", default="", metavar="PREFIX", help="rostool: prefix every topic (before --remap).")
@click.option("--skip-empty", type=click.FloatRange(min=0, min_open=True), metavar="SEC",
              help="rostool: skip gaps of more than SEC seconds without messages.")  # fmt: skip
@click.option("--distro", type=click.Choice(sorted(DISTROS)), default=DEFAULT_DISTRO, show_default=True,
              help="rostool: ROS 2 type store for bags that carry no message definitions.")  # fmt: skip
@parsed_into(PlayFlags)
def play(ctx: click.Context, flags: PlayFlags) -> None:
    """Play back ROS 2 data from a bag, as `ros2 bag play` does.

    BAG is a rosbag2 directory, an .mcap or .db3 file (or a ROS 1 .bag, converted as `bag convert`
    does). The CDR bytes are published unchanged with the bag's types and recorded durability.
    On a terminal, as in rosbag2: space pauses/resumes, the right arrow (or 's') plays the next message
    while paused, up/down raise/lower the rate by 10 %. rosbag2's control services are served while
    playing: /rosbag2_player/pause, resume, toggle_paused, is_paused, get_rate, set_rate, play_next,
    burst, seek and stop (rosbag2_interfaces' types; `-p` can then be resumed without a terminal).

    \b
    Examples:
      rostool --ros2 bag play run/
      rostool --ros2 bag play run/ --topics /chatter /odom -r 2 --start-offset 5
      rostool --ros2 bag play run/ --clock 100 -l
      rostool --ros2 bag play talker.mcap --remap /chatter:=/talk --playback-duration 3
      rostool --ros2 service call /rosbag2_player/set_rate rosbag2_interfaces/srv/SetRate "{rate: 2.0}"
    """
    from rostool.bag.play import PlayOptions, parse_remaps
    from rostool.bag.play_topics import check_storage
    from rostool.bag.qos_overrides import qos_overrides
    from rostool.bag.record_select import event_topic, services_events
    from rostool.commands.bag._playing import PlayRequest, run_play

    until = flags.playback_until_sec
    if flags.playback_until_nsec is not None:
        if until is not None:
            raise RostoolError("give one of --playback-until-sec and --playback-until-nsec")
        until = flags.playback_until_nsec / 1e9
    bags = [*([flags.bag_path] if flags.bag_path else []), *flags.inputs]
    if not bags:
        raise RostoolError("give the bag to play (e.g. `rostool --ros2 bag play run/`)")
    if flags.duration is not None and flags.playback_duration is not None:
        raise RostoolError("choose one of -u/--duration and --playback-duration")
    for bag in bags:
        check_storage(bag, flags.storage)
    qos_overrides(flags.qos_profile_overrides_path, apply=False)
    hz = flags.hz or flags.clock or 40.0
    options = PlayOptions(
        rate=flags.rate,
        start=flags.start_offset,
        duration=flags.playback_duration or flags.duration,
        loop=flags.loop,
        topics=[*topic_list(flags.topics), *sorted(services_events(topic_list(flags.services)))],
        clock=flags.clock is not None,
        hz=hz,
        immediate=flags.immediate,
        keep_alive=flags.keep_alive,
        wait_for_subscribers=flags.wait_for_subscribers,
        match_wait=flags.match_wait,
        remap=parse_remaps(topic_list(flags.remap)),
        prefix=flags.prefix,
        skip_empty=flags.skip_empty,
        delay=flags.delay,
        pause=flags.start_paused,
        exclude=[
            *topic_list(flags.exclude_topics),
            *(event_topic(s) for s in topic_list(flags.exclude_services)),
        ],
        regex=flags.regex or None,
        exclude_regex=flags.exclude_regex or None,
        until=until,
        clock_topics=topic_list(flags.clock_topics),
        clock_topics_all=flags.clock_topics_all,
    )
    request = PlayRequest(
        bags=bags,
        distro=flags.distro,
        options=options,
        ros2_hz=hz,
        quiet=flags.quiet,
        form="ros2 bag",
        keyboard=not flags.disable_keyboard_controls,
        pause_flags=(("-p/--start-paused", flags.start_paused),),
        nothing_played_hint="--start-offset and --topics",
    )
    run_play(ctx, request)
