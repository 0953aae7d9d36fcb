"""`rostool bag record/play` under ROS 2 (--ros2, ROS_VERSION=2 or a detected ROS 2 graph): ros2 bag's forms.

The letters mean what they mean to `ros2 bag` (Jazzy/Kilted): `record -o NAME` is the exact rosbag2
directory, `-s` the storage (mcap, sqlite3), `-b`/`-d` split by size/duration, `--topics a b`; `play -p`
starts paused, `-s` names the storage, `--clock [HZ]`, `--topics a b`, `-m/--remap old:=new`. The
engines are the ROS 1 forms' (rostool/bag/record.py, play.py, play_ros2.py).

ros2 bag's list options take several values (`--topics a b c`); click options take one, so `ListCommand`
rewrites `--topics a b c` into `--topics a --topics b --topics c` before parsing (up to the next `-x`).
"""

from __future__ import annotations

import datetime
import re
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import click

from rostool.commands._common import interfaces_option
from rostool.commands._qos import qos_options
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest
from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
QOS_KEYS = {
    "history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
    "liveliness_lease_duration", "avoid_ros_namespace_conventions",
}  # fmt: skip
HIDDEN = re.compile(r"(^|/)_")  # ROS 2 hidden names: a token starting with an underscore
SERVICE_EVENT = "/_service_event"


class ListCommand(click.Command):
    """A click command whose `list_options` take every value up to the next option, as argparse's nargs='+'.

    `optional_values`: options whose value may be left out (`--clock` alone means `--clock=40`).
    `bag_last`: play's BAG may follow a list (`--topics /a /b BAG`): an existing path ends the list.
    """

    def __init__(
        self,
        *args: Any,
        list_options: Sequence[str] = (),
        optional_values: dict[str, str] | None = None,
        bag_last: bool = False,
        **kwargs: Any,
    ) -> None:
        super().__init__(*args, **kwargs)
        self.list_options = set(list_options)
        self.optional_values = optional_values or {}
        self.bag_last = bag_last

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        return super().parse_args(ctx, self._expand(args))

    def _expand(self, args: list[str]) -> list[str]:
        out: list[str] = []
        i = 0
        while i < len(args):
            arg = args[i]
            i += 1
            if arg == "--":
                out += args[i - 1 :]
                break
            if arg in self.optional_values:
                value = args[i] if i < len(args) else None
                if value is not None and _is_number(value):
                    out.append(f"{arg}={value}")
                    i += 1
                else:
                    out.append(f"{arg}={self.optional_values[arg]}")
                continue
            if arg not in self.list_options:
                out.append(arg)
                continue
            values = []
            while i < len(args) and not (args[i].startswith("-") and len(args[i]) > 1):
                values.append(args[i])
                i += 1
            bag_given = any(Path(a).exists() for a in out if not a.startswith("-"))
            if self.bag_last and values and i == len(args) and not bag_given and Path(values[-1]).exists():
                out.append(values.pop())  # `--topics /a /b BAG`: the bag ends the list
            for value in values:
                out += [arg, value]
        return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _names(values: Sequence[str]) -> list[str]:
    """Values of a list option; one value may also hold several names separated by spaces or commas."""
    return [name for value in values for name in value.replace(",", " ").split()]


def _qos_overrides(path: str | None, apply: bool = True) -> QosRequest | None:
    """--qos-profile-overrides-path: rosbag2's YAML ({topic: {reliability, durability, depth, ...}})."""
    if path is None:
        return None
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as err:
        raise RostoolError(f"--qos-profile-overrides-path {path}: cannot read it: {err}") from err
    if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
        raise RostoolError(
            f"--qos-profile-overrides-path {path}: expected `/topic: {{reliability: ...}}` entries"
        )
    for topic, entry in data.items():
        unknown = sorted(set(entry) - QOS_KEYS)
        if unknown:
            raise RostoolError(
                f"--qos-profile-overrides-path {path}: {topic}: unknown QoS policy {unknown[0]!r}"
            )
        for key in ("deadline", "lifespan", "liveliness_lease_duration"):
            value = entry.get(key)
            if value is not None and not (isinstance(value, dict) and {"sec", "nsec"} <= value.keys()):
                raise RostoolError(
                    f"--qos-profile-overrides-path {path}: {topic} {key}: "
                    "Time overrides must include both seconds and nanoseconds (sec and nsec)"
                )
    if not apply:  # play: checked only; its publishers offer the QoS the bag recorded
        return None
    merged: dict[str, Any] = {}  # one reader QoS for all: the topics' entries must not contradict
    for entry in data.values():
        for key in ("reliability", "durability", "depth"):
            if key not in entry:
                continue
            value = str(entry[key]).lower() if key != "depth" else entry[key]
            if merged.setdefault(key, value) != value:
                raise RostoolError(
                    f"--qos-profile-overrides-path {path}: rostool applies one QoS to every reader, but the "
                    f"topics ask for different {key}; record them in separate runs"
                )
    if not merged:
        return None
    reliability, durability, depth = (merged.get(k) for k in ("reliability", "durability", "depth"))
    for value, allowed in (
        (reliability, ("reliable", "best_effort")),
        (durability, ("volatile", "transient_local")),
    ):
        if value is not None and value not in allowed:
            raise RostoolError(
                f"--qos-profile-overrides-path {path}: {value!r} is not one of {', '.join(allowed)}"
            )
    return QosRequest(None, reliability, durability, int(depth) if depth is not None else None)


# -- record --------------------------------------------------------------------------------------
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
    "--node-name", default="rosbag2_recorder", show_default=True, help="Accepted for ros2 bag's sake."
)
@click.option(
    "--custom-data", multiple=True, metavar="KEY=VALUE...", help="Store KEY=VALUE in metadata.yaml."
)
@click.option(
    "--disable-keyboard-controls", is_flag=True, help="Accepted (no keys are read while recording)."
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
@click.option("--max-cache-duration", type=click.IntRange(min=0), default=0, help="Accepted.")
@click.option("--start-paused", is_flag=True, help="Not supported yet (refused in one line).")
@click.option("--snapshot-mode", is_flag=True, help="Not supported yet (refused in one line).")
@click.option("--ignore-leaf-topics", is_flag=True, help="Not supported yet (refused in one line).")
@click.option("--static-topics-path", metavar="FILE", help="Not supported yet (refused in one line).")
@click.option("--storage-preset-profile", metavar="PROFILE", help="Not supported yet (refused in one line).")
@click.option("--storage-config-file", metavar="FILE", help="Not supported yet (refused in one line).")
@interfaces_option
@qos_options
@click.pass_context
def record(ctx: click.Context, qos: QosRequest, **opts: Any) -> None:
    """Record ROS 2 data to a bag, as `ros2 bag record` does, until Ctrl+C (or --duration).

    Writes a rosbag2 directory (metadata.yaml and NAME_0.mcap, NAME_1.mcap, ...) that ros2 bag, rosbags
    and every rostool bag verb read. Messages are stored as received (CDR) with the publisher's QoS and
    the receive time. With -a/--all-topics/-e/--topic-types, topics that appear later are recorded too.
    Ctrl+C and SIGTERM leave a complete bag (exit 0).

    \b
    Examples:
      rostool --ros2 bag record -a -o run                 # run/metadata.yaml, run/run_0.mcap
      rostool --ros2 bag record --topics /chatter /odom -s sqlite3
      rostool --ros2 bag record -e '/camera/.*' -x compressed -b 1000000000 --max-bag-files 5
      rostool --ros2 bag record -a -d 60 --compression-mode file --compression-format zstd
      rostool --ros2 bag record /chatter -o chatter.mcap  # one .mcap file, no directory
    """
    from rostool.bag.record import Recorder, RecordOptions, stop_on_signals
    from rostool.bag.rosbag2_dir import Rosbag2Layout
    from rostool.commands._common import live_graph

    topics = _names([*opts["positional_topics"], *opts["topics"]])
    services = _names(opts["services"])
    topic_types = _names(opts["topic_types"])
    all_topics = opts["all_"] or opts["all_topics"]
    all_services = opts["all_"] or opts["all_services"]
    regex = opts["regex"]
    for name in ("start_paused", "snapshot_mode", "ignore_leaf_topics", "static_topics_path",
                 "storage_preset_profile", "storage_config_file"):  # fmt: skip
        if opts[name]:
            flag = "--" + name.replace("_", "-")
            raise RostoolError(f"{flag} is not supported by rostool's recorder yet; leave it out")
    _check_record_arguments(opts, topics, services, topic_types, all_topics, all_services)
    if opts["output"] and opts["output_name"]:
        raise RostoolError("choose one of -o/--output and -O/--output-name")
    output = (
        opts["output"] or opts["output_name"] or datetime.datetime.now().strftime("rosbag2_%Y_%m_%d-%H_%M_%S")
    )
    suffix = Path(output).suffix.lower()
    single = suffix in (".mcap", ".db3", ".bag")
    layout = None
    if not single:
        layout = Rosbag2Layout(
            path=Path(output),
            storage=opts["storage"],
            max_size=opts["max_bag_size"],
            max_duration=float(opts["max_bag_duration"]),
            max_files=opts["max_bag_files"],
            compression_mode=opts["compression_mode"],
            compression_format=opts["compression_format"],
            custom_data=dict(_key_value(v) for v in opts["custom_data"]),
        )
        if not opts["force"]:
            from rostool.bag.rosbag2_dir import check_output

            check_output(layout.path)
    elif opts["max_bag_size"] or opts["max_bag_duration"] or opts["compression_mode"] != "none":
        raise RostoolError(f"{output}: one file cannot be split or compressed; give a directory name instead")
    overrides = _qos_overrides(opts["qos_profile_overrides_path"])
    if overrides is not None and qos.given:
        raise RostoolError("choose one of --qos-profile-overrides-path and --qos-*")
    qos = overrides or qos
    selector = _Selector(
        topics=set(topics),
        services={_event_topic(s) for s in services},
        topic_types=set(topic_types),
        all_topics=all_topics,
        all_services=all_services,
        regex=_compile(regex, "-e/--regex"),
        exclude_regex=_compile(opts["exclude_regex"], "-x/--exclude-regex"),
        exclude_topics=set(_names(opts["exclude_topics"])),
        exclude_types=set(_names(opts["exclude_topic_types"])),
        exclude_services={_event_topic(s) for s in _names(opts["exclude_services"])},
        hidden=opts["include_hidden_topics"],
    )
    options = RecordOptions(
        topics=topics,  # subscribed at once: a publisher that appears later is matched by DDS
        output_name=output if single else None,
        fmt={".db3": "db3", ".bag": "bag"}.get(suffix, "mcap"),
        force=opts["force"],
        duration=opts["duration"],
        buffer_bytes=max(opts["max_cache_size"], 1024 * 1024),
        rosbag2=layout,
        wanted=selector,
        use_sim_time=opts["use_sim_time"],
    )
    quiet = opts["quiet"]
    stop = threading.Event()
    with live_graph(ctx, opts["interface_paths"]) as graph:
        graph.use_qos(qos)
        selector.graph = graph

        def warn(text: str) -> None:
            click.echo(f"rostool: warning: {text}", err=True)

        hidden = opts["include_hidden_topics"] or bool(services) or all_services or bool(regex)
        hidden = hidden or any(HIDDEN.search(t) for t in topics)
        source = graph.record_source(warn, hidden)
        recorder = Recorder(source, options)
        if opts["no_discovery"]:
            selector.freeze(source.published_topics())
        if not quiet and sys.stderr.isatty():  # piped, stderr carries only warnings, errors and the summary
            click.echo("[INFO] [rosbag2_recorder]: Listening for topics...", err=True)
            click.echo("[INFO] [rosbag2_recorder]: Recording...", err=True)
        with stop_on_signals(stop):
            result = recorder.run(stop, None)
    for topic, count in sorted(result.dropped.items()):
        warn(f"dropped {count} messages on {topic}: the disk could not keep up (raise --max-cache-size)")
    for topic, why in sorted(result.skipped.items()):
        warn(f"some messages on {topic} were not written: {why}")
    if result.error is not None:
        kept = f"; what was recorded before is in {', '.join(map(str, result.files))}" if result.files else ""
        raise RostoolError(f"recording stopped: {result.error}{kept}")
    if not quiet:
        count = len(result.counts)
        click.echo(
            f"recorded {result.messages} messages on {count} topic{'' if count == 1 else 's'} to "
            + ", ".join(str(p) for p in result.files),
            err=True,
        )


def _check_record_arguments(
    opts: dict[str, Any],
    topics: list[str],
    services: list[str],
    topic_types: list[str],
    all_topics: bool,
    all_services: bool,
) -> None:
    """ros2 bag record's validate_parsed_arguments, message for message."""
    regex = opts["regex"]
    if not (all_topics or all_services or topics or services or topic_types or regex):
        raise RostoolError(
            "Need to specify at least one option out of --all, --all-topics, --all-services, --services, "
            "--topics, --topic-types or --regex"
        )
    if opts["exclude_regex"] and not (all_topics or all_services or topic_types or regex):
        raise RostoolError(
            "--exclude-regex argument requires either --all, --all-topics, --topic-types, "
            "--all-services or --regex"
        )
    if opts["exclude_topics"] and not (all_topics or topic_types or regex):
        raise RostoolError(
            "--exclude-topics argument requires either --all, --all-topics, --topic-types or --regex"
        )
    if opts["exclude_topic_types"] and not (all_topics or topic_types or regex):
        raise RostoolError("--exclude-topic-types argument requires either --all, --all-topics or --regex")
    if opts["exclude_services"] and not (all_services or regex):
        raise RostoolError("--exclude-services argument requires either --all, --all-services or --regex")
    if opts["use_sim_time"] and opts["no_discovery"]:
        raise RostoolError(
            "--use-sim-time and --no-discovery both set, but are incompatible settings: "
            "the /clock topic needs to be discovered to record with sim time"
        )
    if opts["compression_format"] and opts["compression_mode"] == "none":
        raise RostoolError("Invalid choice: Cannot specify compression format without a compression mode.")
    if opts["max_bag_files"] and not (opts["max_bag_size"] or opts["max_bag_duration"]):
        raise RostoolError("--max-bag-files needs --max-bag-size or --max-bag-duration")
    warn = [
        (all_services and services, "--all or --all-services will override --services"),
        (all_topics and topics, "--all or --all-topics will override --topics"),
        (
            (all_topics or all_services) and regex,
            "--all, --all-topics or --all-services will override --regex",
        ),
    ]
    for given, text in warn:
        if given:
            click.echo(f"[WARN] [ros2bag]: {text}", err=True)


def _key_value(entry: str) -> tuple[str, str]:
    key, _, value = entry.partition("=")
    return key, value


def _event_topic(service: str) -> str:
    name = service if service.startswith("/") else "/" + service
    return name if name.endswith(SERVICE_EVENT) else name + SERVICE_EVENT


def _compile(pattern: str, flag: str) -> re.Pattern[str] | None:
    if not pattern:
        return None
    try:
        return re.compile(pattern)
    except re.error as err:
        raise RostoolError(f"{flag} {pattern!r}: bad regular expression: {err}") from err


class _Selector:
    """Which discovered topics ros2 bag record takes (rosbag2_transport's topic filter rules)."""

    def __init__(self, **rules: Any) -> None:
        self.rules = rules
        self.graph: Any = None
        self._decided: dict[str, bool] = {}
        self._frozen: set[str] | None = None

    def freeze(self, present: list[str]) -> None:
        """--no-discovery: only what is there now."""
        self._frozen = set(present)

    def __call__(self, topic: str) -> bool:
        known = self._decided.get(topic)
        if known is not None:
            return known
        if self._frozen is not None and topic not in self._frozen:
            return False
        decision = self._decide(topic)
        if decision is not None:
            self._decided[topic] = decision
        return bool(decision)

    def _type(self, topic: str) -> str | None:
        try:
            return self.graph.topic_type(topic) if self.graph is not None else None
        except RostoolError:
            return None

    def _decide(self, topic: str) -> bool | None:
        """True/False, or None while the type it depends on is not known yet."""
        r = self.rules
        is_service = topic.endswith(SERVICE_EVENT)
        if r["exclude_regex"] is not None and r["exclude_regex"].search(topic):
            return False
        if is_service:
            if topic in r["exclude_services"]:
                return False
            wanted = r["all_services"] or topic in r["services"]
            return wanted or bool(r["regex"] is not None and r["regex"].search(topic))
        if topic in r["exclude_topics"]:
            return False
        if HIDDEN.search(topic) and not r["hidden"] and topic not in r["topics"]:
            return False
        needs_type = bool(r["topic_types"] or r["exclude_types"])
        type_name = self._type(topic) if needs_type else None
        if needs_type and type_name is None:
            return None
        if type_name in r["exclude_types"]:
            return False
        if r["all_topics"] or topic in r["topics"] or type_name in r["topic_types"]:
            return True
        return bool(r["regex"] is not None and r["regex"].search(topic))


# -- play ----------------------------------------------------------------------------------------
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
@click.option("-p", "--start-paused", is_flag=True, help="Start paused (space resumes; needs a terminal).")
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
@click.option("--wait-for-subscribers", is_flag=True, help="rostool: wait for a subscriber on every topic.")
@click.option("--prefix", default="", metavar="PREFIX", help="rostool: prefix every topic (before --remap).")
@click.option("--skip-empty", type=click.FloatRange(min=0, min_open=True), metavar="SEC",
              help="rostool: skip gaps of more than SEC seconds without messages.")  # fmt: skip
@click.option("--distro", type=click.Choice(sorted(DISTROS)), default=DEFAULT_DISTRO, show_default=True,
              help="rostool: ROS 2 type store for bags that carry no message definitions.")  # fmt: skip
@click.pass_context
def play(ctx: click.Context, **opts: Any) -> None:
    """Play back ROS 2 data from a bag, as `ros2 bag play` does.

    BAG is a rosbag2 directory, an .mcap or .db3 file (or a ROS 1 .bag, converted as `bag convert`
    does). The CDR bytes are published unchanged with the bag's types and recorded durability.
    On a terminal, space pauses/resumes and 's' steps while paused.

    \b
    Examples:
      rostool --ros2 bag play run/
      rostool --ros2 bag play run/ --topics /chatter /odom -r 2 --start-offset 5
      rostool --ros2 bag play run/ --clock 100 -l
      rostool --ros2 bag play talker.mcap --remap /chatter:=/talk --playback-duration 3
    """
    from rostool.bag.play import Console, PlayOptions, parse_remaps
    from rostool.bag.play_ros2 import Ros2Player
    from rostool.bag.reader import BagReader
    from rostool.commands._common import live_graph

    until = opts["playback_until_sec"]
    if opts["playback_until_nsec"] is not None:
        if until is not None:
            raise RostoolError("give one of --playback-until-sec and --playback-until-nsec")
        until = opts["playback_until_nsec"] / 1e9
    bags = [*([opts["bag_path"]] if opts["bag_path"] else []), *opts["inputs"]]
    if not bags:
        raise RostoolError("give the bag to play (e.g. `rostool --ros2 bag play run/`)")
    if opts["duration"] is not None and opts["playback_duration"] is not None:
        raise RostoolError("choose one of -u/--duration and --playback-duration")
    for bag in bags:
        _check_storage(bag, opts["storage"])
    _qos_overrides(opts["qos_profile_overrides_path"], apply=False)
    services = {_event_topic(s) for s in _names(opts["services"])}
    options = PlayOptions(
        rate=opts["rate"],
        start=opts["start_offset"],
        duration=opts["playback_duration"] or opts["duration"],
        loop=opts["loop"],
        topics=[*_names(opts["topics"]), *sorted(services)],
        clock=opts["clock"] is not None,
        hz=opts["hz"] or opts["clock"] or 40.0,
        immediate=opts["immediate"],
        keep_alive=opts["keep_alive"],
        wait_for_subscribers=opts["wait_for_subscribers"],
        prefix=opts["prefix"],
        skip_empty=opts["skip_empty"],
        delay=opts["delay"],
        remap=parse_remaps(_names(opts["remap"])),
        pause=opts["start_paused"],
        exclude=[
            *_names(opts["exclude_topics"]),
            *(_event_topic(s) for s in _names(opts["exclude_services"])),
        ],
        regex=opts["regex"] or None,
        exclude_regex=opts["exclude_regex"] or None,
        until=until,
        clock_topics=_names(opts["clock_topics"]),
        clock_topics_all=opts["clock_topics_all"],
    )
    quiet = opts["quiet"]
    warn: Callable[[str], None] = (
        (lambda text: None) if quiet else (lambda text: click.echo(f"rostool: warning: {text}", err=True))
    )
    with BagReader(bags, opts["distro"]) as reader, live_graph(ctx) as graph:
        console = Console.detect(quiet)
        if opts["disable_keyboard_controls"]:
            console.keyboard = False
        if graph.encoding != "cdr":
            raise RostoolError("the ROS 2 form of bag play needs a ROS 2 graph")
        _only_present(options, reader, graph.resolve, warn)
        player = Ros2Player(reader, graph, options, console, warn)
        if options.pause and not console.keyboard:
            raise RostoolError("-p/--start-paused needs a terminal on stdin to resume with space")
        with console:
            player.advertise()
            result = player.run()
    if result.published == 0 and not quiet:
        click.echo("rostool: warning: no message was played (check --start-offset and --topics)", err=True)
    sys.stdout.flush()


def _only_present(
    options: Any, reader: Any, resolve: Callable[[str], str], warn: Callable[[str], None]
) -> None:
    """ros2 bag play plays what it can of --topics/--services: names the bag lacks are left out (warned)."""
    if not options.topics:
        return
    wanted = [resolve(t) for t in options.topics]
    present = [t for t in wanted if t in reader.topics]
    missing = [t for t in wanted if t not in reader.topics]
    if missing and not present:
        have = ", ".join(sorted(reader.topics)) or "none"
        raise RostoolError(f"topic {missing[0]} is not in the bag (topics: {have})")
    for name in missing:
        warn(f"{name} is not in the bag; playing the other topics")
    options.topics = present


def _check_storage(path: str, storage: str | None) -> None:
    """`-s STORAGE` must name the bag's storage (ros2 bag fails to open it otherwise)."""
    if storage is None:
        return
    from rostool.bag.open import detect

    bag = detect(path)
    found = {"db3": "sqlite3"}.get(bag.storage, bag.storage)
    if found != storage:
        raise RostoolError(f"{path}: -s {storage} given, but the bag's storage is {found}")
