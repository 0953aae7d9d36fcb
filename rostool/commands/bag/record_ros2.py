"""`rostool bag record` with ros2 bag record's flags (under ROS 2: --ros2, ROS_VERSION=2 or a detected ROS 2
graph). The letters mean what they mean to `ros2 bag` (Jazzy/Kilted): `-o NAME` is the exact rosbag2
directory, `-s` the storage (mcap, sqlite3), `-b`/`-d` split by size/duration, `--topics a b`."""

from __future__ import annotations

import datetime
from pathlib import Path

import click

from rostool.commands._common import interfaces_option
from rostool.commands._qos import qos_options
from rostool.commands.bag._flags import ListCommand, parsed_into
from rostool.commands.bag._options import CONTEXT, max_rate_option, progress_option
from rostool.commands.bag._record_ros2_flags import (
    RecordFlags,
    check_flags,
    discovers,
    static_topics,
    topic_rules,
)
from rostool.errors import RostoolError

RECORD_LISTS = (
    "--topics", "--services", "--topic-types", "--exclude-topics", "--exclude-topic-types",
    "--exclude-services", "--custom-data",
)  # fmt: skip


@click.command(
    cls=ListCommand,
    list_options=RECORD_LISTS,
    context_settings=CONTEXT,
    short_help="Record ROS 2 data to a bag.",
)
@click.argument("positional_topics", nargs=-1, metavar="[TOPIC]...")
@click.option("-o", "--output", metavar="DIR",
              help="The bag to create: a rosbag2 directory of exactly this name (default: "
                   "rosbag2_YYYY_MM_DD-HH_MM_SS); a name ending in .mcap/.db3 writes one file.")  # fmt: skip
@click.option("-s", "--storage", type=click.Choice(["mcap", "sqlite3"]), default="mcap", show_default=True,
              help="Storage of the rosbag2 directory.")  # fmt: skip
@click.option("--topics", "topics", multiple=True, metavar="TOPIC...", help="Topics to record.")
@click.option("--services", multiple=True, metavar="SERVICE...",
              help="Services to record (their /_service_event topics; needs introspection).")  # fmt: skip
@click.option("--topic-types", multiple=True, metavar="TYPE...", help="Record the topics of these types.")
@click.option(
    "-a", "--all", "all_", is_flag=True, help="Record all topics and services (hidden ones left out)."
)
@click.option("--all-topics", is_flag=True, help="Record all topics (hidden ones left out).")
@click.option("--all-services", is_flag=True, help="Record all services via their service event topics.")
@click.option(
    "-e", "--regex", default="", metavar="RE", help="Record topics and services whose name contains RE."
)
@click.option("-x", "--exclude-regex", default="", metavar="RE", help="Leave out names containing RE.")
@click.option("--exclude-topics", multiple=True, metavar="TOPIC...", help="Leave out these topics.")
@click.option(
    "--exclude-topic-types", multiple=True, metavar="TYPE...", help="Leave out topics of these types."
)
@click.option("--exclude-services", multiple=True, metavar="SERVICE...", help="Leave out these services.")
@click.option(
    "--include-hidden-topics", is_flag=True, help="Discover and record hidden topics (/_name) as well."
)
@click.option(
    "--include-unpublished-topics", is_flag=True, help="Also subscribe to --topics nobody publishes yet."
)
@click.option("--no-discovery", is_flag=True, help="Record only topics present at startup.")
@click.option("-p", "--polling-interval", type=click.IntRange(min=1), default=100, show_default=True,
              metavar="MS", help="Milliseconds between looking for new topics.")  # fmt: skip
@click.option("--qos-profile-overrides-path", type=click.Path(exists=True, dir_okay=False), metavar="FILE",
              help="YAML of QoS per topic (rostool applies one profile to all readers).")  # fmt: skip
@click.option("-f", "--serialization-format", type=click.Choice(["cdr"]), default="cdr", show_default=True,
              help="Serialization format of the stored messages.")  # fmt: skip
@click.option("-b", "--max-bag-size", type=click.IntRange(min=0), default=0, metavar="BYTES",
              help="Split the bag into a new file at this size (0: one file).")  # fmt: skip
@click.option("-d", "--max-bag-duration", type=click.IntRange(min=0), default=0, metavar="S",
              help="Split the bag into a new file after S seconds (0: one file).")  # fmt: skip
@click.option("--max-bag-files", type=click.IntRange(min=0), default=0, metavar="N",
              help="Keep at most N files, deleting the oldest (needs -b or -d).")  # fmt: skip
@click.option("--max-cache-size", type=click.IntRange(min=0), default=100 * 1024 * 1024, metavar="BYTES",
              help="Messages held for the disk; beyond it they are dropped and counted.")  # fmt: skip
@click.option("--compression-mode", type=click.Choice(["none", "file", "message"]), default="none",
              show_default=True, help="Compress each file or each message.")  # fmt: skip
@click.option("--compression-format", type=click.Choice(["", "zstd"]), default="",
              help="Compression algorithm (zstd).")  # fmt: skip
@click.option("--use-sim-time", is_flag=True,
              help="Stamp messages with /clock's time; none is written before the first.")  # fmt: skip
@click.option(
    "--node-name",
    default="rosbag2_recorder",
    show_default=True,
    help="The recorder's node name: --snapshot-mode serves NAME/snapshot.",
)
@click.option(
    "--custom-data", multiple=True, metavar="KEY=VALUE...", help="Store KEY=VALUE in metadata.yaml."
)
@click.option(
    "--disable-keyboard-controls", is_flag=True, help="Read no keys (SPACE pauses/resumes otherwise)."
)
@click.option("--log-level", type=click.Choice(["debug", "info", "warn", "error", "fatal"]), default="info",
              help="Accepted for ros2 bag's sake.")  # fmt: skip
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), metavar="S",
              help="rostool: stop after S seconds.")  # fmt: skip
@click.option("-q", "--quiet", is_flag=True, help="rostool: no progress and no summary on stderr.")
@click.option("-O", "--output-name", metavar="NAME",
              help="rostool: like -o; NAME.bag writes a ROS 1 bag (messages converted).")  # fmt: skip
@click.option("--force", is_flag=True, help="rostool: replace an existing output bag (nothing else).")
@click.option("--compression-queue-size", type=click.IntRange(min=0), default=1, help="Accepted.")
@click.option("--compression-threads", type=click.IntRange(min=0), default=0, help="Accepted.")
@click.option("--compression-threads-priority", type=int, default=0, help="Accepted.")
@click.option("--max-cache-duration", type=click.IntRange(min=0), default=0, metavar="S",
              help="With --snapshot-mode: hold the last S seconds of messages at most (0: any).")  # fmt: skip
@click.option("--start-paused", is_flag=True,
              help="Start paused: nothing is recorded until SPACE (or SIGUSR1) resumes.")  # fmt: skip
@click.option("--snapshot-mode", is_flag=True,
              help="Hold the newest messages in memory (--max-cache-size/-duration); write them on 's' "
                   "or SIGUSR2.")  # fmt: skip
@click.option("--ignore-leaf-topics", is_flag=True,
              help="Leave out discovered topics no one subscribes to (until someone does).")  # fmt: skip
@click.option("--static-topics-path", metavar="FILE",
              help="YAML `static_topics_and_types_list: [[/topic, pkg/msg/Type], ...]`: subscribe to these "
                   "at once with these types, before any publisher is seen.")  # fmt: skip
@click.option("--storage-preset-profile", metavar="PROFILE",
              help="rosbag2's storage presets: fastwrite, zstd_fast, zstd_small (mcap); resilient "
                   "(sqlite3).")  # fmt: skip
@click.option("--storage-config-file", type=click.Path(exists=True, dir_okay=False), metavar="FILE",
              help="YAML options of the storage: mcap writer options (chunkSize, compression, ...) or "
                   "sqlite3 pragmas (write: {pragmas: [...]}).")  # fmt: skip
@max_rate_option
@progress_option
@interfaces_option
@qos_options
@parsed_into(RecordFlags)
def record(ctx: click.Context, flags: RecordFlags) -> None:
    """Record ROS 2 data to a bag, as `ros2 bag record` does, until Ctrl+C (or --duration).

    Writes a rosbag2 directory (metadata.yaml and NAME_0.mcap, NAME_1.mcap, ...) that ros2 bag, rosbags
    and every rostool bag verb read. Messages are stored as received (CDR) with the publisher's QoS and
    the receive time. With -a/--all-topics/-e/--topic-types, topics that appear later are recorded too;
    --static-topics-path's topics are subscribed at once with their given types, so a publisher that starts
    later is recorded from its first message.
    Ctrl+C and SIGTERM leave a complete bag (exit 0). On a terminal SPACE (or SIGUSR1) pauses and resumes,
    and a dashboard shows each topic's messages, rate, bandwidth, bytes written and drops. rosbag2's
    recorder services are served: /rosbag2_recorder/pause, resume, is_paused, split_bagfile (and snapshot
    with --snapshot-mode; the node is --node-name).

    \b
    Examples:
      rostool --ros2 bag record -a -o run                 # run/metadata.yaml, run/run_0.mcap
      rostool --ros2 bag record --topics /chatter /odom -s sqlite3
      rostool --ros2 bag record -e '/camera/.*' -x compressed -b 1000000000 --max-bag-files 5
      rostool --ros2 bag record -a -d 60 --compression-mode file --compression-format zstd
      rostool --ros2 bag record /chatter -o chatter.mcap  # one .mcap file, no directory
      rostool --ros2 bag record -a --start-paused         # SPACE starts recording
      rostool --ros2 bag record -a --max-rate /points:5   # at most 5 point clouds a second
      rostool --ros2 bag record -a --storage-preset-profile zstd_fast
      rostool --ros2 bag record -a --storage-config-file mcap_writer_options.yaml
      rostool --ros2 bag record -a --snapshot-mode        # then: service call /rosbag2_recorder/snapshot
      rostool --ros2 bag record --static-topics-path static.yaml  # subscribed before any publisher
    """
    from rostool.bag.qos_overrides import qos_overrides
    from rostool.bag.record_options import RecordOptions, parse_max_rates
    from rostool.bag.record_select import TopicSelector
    from rostool.bag.rosbag2_dir import Rosbag2Layout
    from rostool.commands.bag._recording import RecordRequest, run_record

    check_flags(flags)
    rules = topic_rules(flags)
    static = static_topics(flags, rules)  # a bad file is refused before anything is made
    if flags.output and flags.output_name:
        raise RostoolError("choose one of -o/--output and -O/--output-name")
    output = (
        flags.output or flags.output_name or datetime.datetime.now().strftime("rosbag2_%Y_%m_%d-%H_%M_%S")
    )
    suffix = Path(output).suffix.lower()
    single = suffix in (".mcap", ".db3", ".bag")
    layout = None
    if not single:
        layout = Rosbag2Layout(
            path=Path(output),
            storage=flags.storage,
            max_size=flags.max_bag_size,
            max_duration=float(flags.max_bag_duration),
            max_files=flags.max_bag_files,
            compression_mode=flags.compression_mode,
            compression_format=flags.compression_format,
            custom_data=dict(entry.partition("=")[::2] for entry in flags.custom_data),
        )
        if not flags.force:
            from rostool.bag.rosbag2_dir import check_output

            check_output(layout.path)
    elif flags.max_bag_size or flags.max_bag_duration or flags.compression_mode != "none":
        raise RostoolError(f"{output}: one file cannot be split or compressed; give a directory name instead")
    storage_config = None
    if flags.storage_config_file or flags.storage_preset_profile:
        from rostool.bag.storage_config import load_storage_config

        if suffix == ".bag":
            raise RostoolError("--storage-config-file and --storage-preset-profile configure mcap and "
                               "sqlite3 storage, not a ROS 1 .bag")  # fmt: skip
        storage = {".db3": "sqlite3", ".mcap": "mcap"}.get(suffix, flags.storage)
        storage_config = load_storage_config(flags.storage_config_file, storage, flags.storage_preset_profile)
        if layout is not None:
            layout.storage_config = storage_config
    overrides = qos_overrides(flags.qos_profile_overrides_path)
    if overrides is not None and flags.qos.given:
        raise RostoolError("choose one of --qos-profile-overrides-path and --qos-*")
    selector = TopicSelector(rules)
    options = RecordOptions(
        topics=flags.topic_names,  # subscribed at once: a publisher that appears later is matched by DDS
        output_name=output if single else None,
        fmt={".db3": "db3", ".bag": "bag"}.get(suffix, "mcap"),
        force=flags.force,
        duration=flags.duration,
        buffer_bytes=max(flags.max_cache_size, 1024 * 1024),
        rosbag2=layout,
        wanted=selector if discovers(flags) else None,  # static topics only: nothing is looked for
        use_sim_time=flags.use_sim_time,
        start_paused=flags.start_paused,
        max_rates=parse_max_rates(flags.max_rate),
        snapshot=flags.snapshot_mode,
        snapshot_seconds=float(flags.max_cache_duration),
        storage_config=storage_config,
        static_topics=static,
    )
    request = RecordRequest(
        options=options,
        qos=overrides or flags.qos,
        interface_paths=flags.interface_paths,
        include_hidden=flags.hidden_topics_needed,
        quiet=flags.quiet,
        form="ros2 bag",
        selector=selector,
        no_discovery=flags.no_discovery,
        keyboard=not flags.disable_keyboard_controls,
        progress_every=flags.progress,
        node_name=flags.node_name,
    )
    run_record(ctx, request)
