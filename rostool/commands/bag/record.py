"""`rostool bag record` with rosbag record's flags (ROS 1; the ROS 2 form is record_ros2.py)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import click

from rostool.commands._common import interfaces_option
from rostool.commands._qos import qos_options
from rostool.commands.bag._flags import parsed_into
from rostool.commands.bag._options import CONTEXT, max_rate_option, progress_option
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest


@dataclass(frozen=True)
class RecordFlags:
    topics: tuple[str, ...]
    all_topics: bool
    regex: bool
    exclude: str | None
    output_name: str | None
    output_prefix: str | None
    duration: str | None
    size: float | None
    split: bool
    max_splits: int | None
    limit: int | None
    node: str | None
    fmt: Literal["bag", "mcap", "db3"] | None
    buffsize: int
    compression: str | None
    quiet: bool
    force: bool
    include_hidden_topics: bool
    start_paused: bool
    max_rate: tuple[str, ...]
    progress: float
    interface_paths: tuple[str, ...]
    qos: QosRequest


@click.command(context_settings=CONTEXT)
@click.argument("topics", nargs=-1, metavar="[TOPIC]...")
@click.option("-a", "--all", "all_topics", is_flag=True, help="Record every published topic (also new ones).")
@click.option("-e", "--regex", is_flag=True, help="TOPICs are regular expressions (matching whole names).")
@click.option("-x", "--exclude", metavar="RE", help="Leave out topics matching RE.")
@click.option("-O", "--output-name", metavar="NAME", help="Write exactly NAME (.bag added if missing).")
@click.option("-o", "--output-prefix", metavar="PREFIX", help="Write PREFIX_YYYY-MM-DD-HH-MM-SS.bag.")
@click.option("--duration", metavar="D", help="Stop after D (30, 30s, 5m, 1h); with --split: per file.")
@click.option("--size", type=click.FloatRange(min=0, min_open=True), metavar="MB",
              help="Stop at MB megabytes; with --split: per file.")  # fmt: skip
@click.option("--split", is_flag=True, help="Start a new file (NAME_0, NAME_1, ...) at --size or --duration.")
@click.option("--max-splits", type=click.IntRange(min=1), metavar="N",
              help="With --split: keep at most N files, deleting the oldest.")  # fmt: skip
@click.option("-l", "--limit", type=click.IntRange(min=1), metavar="N",
              help="Record at most N messages per topic (ends when every topic has them).")  # fmt: skip
@click.option("--node", metavar="NODE", help="Record the topics NODE subscribes to (also ones added later).")
@click.option("--format", "fmt", type=click.Choice(["bag", "mcap", "db3"]),
              help="Output format (default: from -O/-o's suffix, else .bag).")  # fmt: skip
@click.option("-b", "--buffsize", type=click.IntRange(min=1), default=256, show_default=True, metavar="MB",
              help="Messages waiting for the disk; beyond it they are dropped (and counted).")  # fmt: skip
@click.option("--lz4", "compression", flag_value="lz4", help="Compress .bag chunks with lz4.")
@click.option("-j", "--bz2", "compression", flag_value="bz2", help="Compress .bag chunks with bz2.")
@click.option("-q", "--quiet", is_flag=True, help="No progress and no summary on stderr.")
@click.option("--force", is_flag=True, help="Replace an existing output bag (nothing else).")
@click.option("--include-hidden-topics", is_flag=True, help="ROS 2: -a/-e also record hidden topics (/_x).")
@click.option("--start-paused", is_flag=True,
              help="Start paused: nothing is recorded until space (or SIGUSR1) resumes.")  # fmt: skip
@max_rate_option
@progress_option
@interfaces_option
@qos_options
@parsed_into(RecordFlags)
def record(ctx: click.Context, flags: RecordFlags) -> None:
    """Record topics of the live graph into a bag, until Ctrl+C (or --duration / --size).

    Messages are stored as received, with their publisher's type and definition and the receive time.
    The bag is written as NAME.bag.active and renamed when recording ends; Ctrl+C and SIGTERM always
    leave a complete, indexed bag (exit 0). After a crash or `kill -9`, `rostool bag reindex
    NAME.bag.active` recovers all but the last 0.1 s. .mcap/.db3 outputs are ROS 2 bags (types
    converted to pkg/msg/T). With -a or -e, topics that appear later are recorded too. On a terminal,
    space pauses and resumes (SIGUSR1 too) and a dashboard shows each topic's messages, rate, bandwidth,
    bytes written and drops.

    These are rosbag record's flags (ROS 1); under ROS 2 (--ros2, ROS_VERSION=2) `bag record` takes ros2
    bag record's and writes a rosbag2 directory (see `rostool --ros2 bag record -h`).

    \b
    Examples:
      rostool bag record -a -O test.bag
      rostool bag record /odom /tf -o run             # run_2024-05-01-12-00-00.bag
      rostool bag record -e '/camera/.*' -x '.*compressed.*' --split --size 1024 --max-splits 5
      rostool bag record --node /move_base -l 100
      rostool bag record -a --duration 30s --format mcap
      rostool bag record -a --max-rate /camera/image_raw:2   # at most 2 images a second
    """
    from rostool.bag.record_options import RecordOptions, parse_max_rates
    from rostool.commands.bag._recording import RecordRequest, run_record

    if flags.output_name and flags.output_prefix:
        raise RostoolError("choose one of -O (exact name) and -o (prefix)")
    if flags.regex and not flags.topics:
        raise RostoolError("-e needs at least one regular expression (e.g. `-e '/camera/.*'`)")
    options = RecordOptions(
        topics=flags.topics,
        all_topics=flags.all_topics,
        regex=flags.regex,
        exclude=flags.exclude,
        size=None if flags.size is None else int(flags.size * 1024 * 1024),
        output_name=flags.output_name,
        output_prefix=flags.output_prefix,
        fmt=flags.fmt,
        duration=_parse_duration(flags.duration),
        buffer_bytes=flags.buffsize * 1024 * 1024,
        split=flags.split,
        max_splits=flags.max_splits,
        limit=flags.limit,
        compression=flags.compression or "none",
        node=flags.node,
        force=flags.force,
        start_paused=flags.start_paused,
        max_rates=parse_max_rates(flags.max_rate),
    )
    if flags.compression and options.fmt not in (None, "bag"):
        raise RostoolError("--lz4/--bz2 compress ROS 1 .bag chunks; leave them out with --format mcap/db3")
    request = RecordRequest(
        options=options,
        qos=flags.qos,
        interface_paths=flags.interface_paths,
        include_hidden=flags.include_hidden_topics,
        quiet=flags.quiet,
        form="rosbag",
        progress_every=flags.progress,
    )
    run_record(ctx, request)


def _parse_duration(text: str | None) -> float | None:
    """rosbag's durations: 30, 30s, 5m, 1.5h."""
    if text is None:
        return None
    value = text.strip().lower()
    scale = {"s": 1.0, "m": 60.0, "h": 3600.0}.get(value[-1:])
    try:
        seconds = float(value[:-1] if scale else value) * (scale or 1.0)
    except ValueError as err:
        raise RostoolError(f"--duration {text!r}: expected seconds, or a number with s, m or h") from err
    if seconds <= 0:
        raise RostoolError(f"--duration {text!r}: must be positive")
    return seconds
