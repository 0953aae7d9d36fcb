"""`rostool bag`: info, echo, convert, filter, reindex over .bag, rosbag2 directories, .mcap and .db3.

Thin: parse options, call one function of `rostool.bag`, render. New verbs (play, record) are added
with `@bag.command()` like the ones below.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import click

from rostool.bag.many import BagItem
from rostool.commands._common import ExtensibleGroup, interfaces_option
from rostool.commands._qos import qos_options
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest
from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
TIME_HELP = "seconds since the epoch, or +S for S seconds after the bag's first message"


@click.group(
    cls=ExtensibleGroup,
    context_settings=CONTEXT,
    extra={
        "export": "rostool.commands.bag_export:export",
        "plot": "rostool.commands.bag_plot:plot",
        "graph": "rostool.commands.bag_graph:graph",
    },
    ros2_forms={
        "record": "rostool.commands.bag_ros2:record",
        "play": "rostool.commands.bag_ros2:play",
    },
)
def bag() -> None:
    """Inspect, convert and repair bags: ROS 1 .bag, rosbag2 directories, .mcap and .db3 files.

    \b
    Examples:
      rostool bag info run.bag
      rostool bag echo run.bag /odom -n 3
      rostool bag convert run.bag run.mcap
      rostool bag filter run.bag out.bag --filter 'm.linear.x > 0'
    """


def distro_option(func: Callable[..., Any]) -> Callable[..., Any]:
    return click.option(
        "--distro",
        type=click.Choice(sorted(DISTROS)),
        default=DEFAULT_DISTRO,
        show_default=True,
        help="ROS 2 type store for bags that carry no message definitions.",
    )(func)


jobs_option = click.option(
    "-j",
    "--jobs",
    type=click.IntRange(min=1),
    metavar="N",
    help="Work on N bags at once, in parallel processes (default: the number of cores, once the bags "
    "hold 64 MB or more).",
)


def _topic_list(values: Sequence[str]) -> list[str]:
    """`--topics /a --topics /b`, `--topics "/a /b"` and `--topics /a,/b` all work."""
    return [name for value in values for name in value.replace(",", " ").split()]


# -- info ----------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
@click.argument("bags", nargs=-1, required=True, metavar="BAG...")
@click.option("--json", "as_json", is_flag=True, help="One JSON object (a list for several bags).")
@click.option("--yaml", "as_yaml", is_flag=True, help="YAML with `rosbag info --yaml`'s keys.")
@click.option("--freq", is_flag=True, help="Also show each topic's rate (reads message timestamps).")
@click.option("-t", "--topic-name", is_flag=True, help="Only the topic names, one a line (ros2 bag info -t).")
@click.option("-v", "--verbose", is_flag=True,
              help="rosbag2 bags: also count each service's requests and responses.")  # fmt: skip
@jobs_option
def info(
    bags: tuple[str, ...], as_json: bool, as_yaml: bool, freq: bool, topic_name: bool, verbose: bool,
    jobs: int | None,
) -> None:  # fmt: skip
    """Summarize bags from their index: duration, size, counts, types and topics.

    Several bags, or a directory of bags (searched recursively; a rosbag2 directory is one bag), are
    read in parallel processes and printed in order.

    \b
    Examples:
      rostool bag info run.bag
      rostool bag info rosbag2_dir/ --json | jq '.topics[] | select(.count > 0) | .name'
      rostool bag info a.bag b.mcap --yaml
      rostool bag info fleet/ -j 2 --json
      rostool bag info rosbag2_dir/ -t                # topic names only, as ros2 bag info -t
    """
    from functools import partial

    from rostool.bag.info import format_text, to_rosbag_yaml
    from rostool.bag.many import expand, successes

    if as_json and as_yaml:
        raise RostoolError("choose one of --json and --yaml")
    items = expand(bags)
    infos = [value for _item, value in successes(partial(_info_one, freq), items, jobs, "reading")]
    if as_json:
        from rostool.output.json_text import dumps

        click.echo(dumps(infos[0].to_dict() if len(infos) == 1 else [i.to_dict() for i in infos]))
    elif as_yaml:
        import yaml

        data = [to_rosbag_yaml(i) for i in infos]
        click.echo(yaml.safe_dump(data[0] if len(data) == 1 else data, sort_keys=False).rstrip("\n"))
    else:
        separator = "\n" if topic_name else "\n\n"
        click.echo(separator.join(format_text(i, verbose=verbose, topic_name=topic_name) for i in infos))


def _info_one(freq: bool, item: BagItem) -> Any:
    from rostool.bag.info import bag_info

    return bag_info(item.path, freq=freq)


# -- echo ----------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
@click.argument("args", nargs=-1, required=True, metavar="BAG... [TOPIC]...")
@click.option("-n", "count", type=click.IntRange(min=1), help="Stop after N messages (of each bag).")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per line.")
@click.option("--csv", "as_csv", is_flag=True, help="CSV like `rostopic echo -p` (one topic).")
@click.option("--field", "fields", multiple=True, metavar="F", help="Print only this field (repeatable).")
@click.option("--noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--nostr", is_flag=True, help="Show strings as their length.")
@click.option("--filter", "expr", metavar="EXPR", help="Keep messages where EXPR holds (names: m, topic, t).")
@click.option("--start", metavar="S", help=f"First message time: {TIME_HELP}.")
@click.option("--end", metavar="S", help=f"Last message time: {TIME_HELP}.")
@jobs_option
@distro_option
def echo(
    args: tuple[str, ...],
    count: int | None,
    as_json: bool,
    as_csv: bool,
    fields: tuple[str, ...],
    noarr: bool,
    nostr: bool,
    expr: str | None,
    start: str | None,
    end: str | None,
    jobs: int | None,
    distro: str,
) -> None:
    """Print the messages of a bag, as `rostopic echo -b` (ROS 1) or `ros2 topic echo` (ROS 2) would.

    Every YAML message ends with a `---` line. When more than one topic is printed (several TOPICs,
    or none given and the bag has several), each message is preceded by a comment line
    `# TOPIC @ SECONDS` (grep -A for it); with --json each line is then
    {"topic": ..., "t": seconds, "msg": {...}} instead of the bare message.

    Several bags (the leading arguments that exist as paths), or a directory of bags, are read in
    parallel processes and printed one after the other in order: YAML output starts each bag with a
    `# bag: PATH` line, and each JSON line is {"bag": NAME, "topic": ..., "t": ..., "msg": {...}}.

    \b
    Examples:
      rostool bag echo run.bag /turtle1/pose -n 2
      rostool bag echo run.bag /turtle1/pose --field x --csv
      rostool bag echo rosbag2_dir /chatter --json --filter 'm.data.startswith("hello")'
      rostool bag echo run.bag --filter 'topic == "/rosout" and m.level >= 4'
      rostool bag echo fleet/ /odom --json -j 2 | jq .msg.pose.pose.position.x
    """
    from rostool.bag.many import expand

    if as_json and as_csv:
        raise RostoolError("choose one of --json and --csv")
    paths, topics = _bags_then_topics(args)
    items = expand(paths)
    mode = "json" if as_json else "csv" if as_csv else "yaml"
    settings = EchoSettings(topics, count, mode, fields, noarr, nostr, expr, start, end, distro)
    if len(items) == 1:
        _echo_bag(items[0].path, settings, sys.stdout.write, None)
        sys.stdout.flush()
        return
    if as_csv:
        raise RostoolError("--csv prints one bag: for several, use `rostool bag export --format csv`")
    _echo_many(items, settings, jobs)


@dataclass(frozen=True)
class EchoSettings:
    topics: tuple[str, ...]
    count: int | None
    mode: Any
    fields: tuple[str, ...]
    noarr: bool
    nostr: bool
    expr: str | None
    start: str | None
    end: str | None
    distro: str


def _bags_then_topics(args: Sequence[str]) -> tuple[list[str], tuple[str, ...]]:
    """The leading arguments that exist as paths are bags (at least the first), the rest topics."""
    from pathlib import Path

    count = 1
    while count < len(args) and Path(args[count]).exists():
        count += 1
    return list(args[:count]), tuple(args[count:])


def _echo_bag(path: Any, settings: EchoSettings, write: Callable[[str], Any], bag_name: str | None) -> None:
    """Print one bag; `bag_name` is set when it is one of several (JSON lines then name it)."""
    from rostool.bag.convert import parse_time
    from rostool.bag.reader import BagReader
    from rostool.output.echo import EchoRenderer
    from rostool.output.json_text import dumps

    with BagReader([path], settings.distro) as reader:
        if bag_name is not None and settings.topics:  # a fleet: a topic some bags lack is not an error
            conns = reader.select([name for name in settings.topics if name in reader.topics])
            conns = conns if any(name in reader.topics for name in settings.topics) else []
        else:
            conns = reader.select(settings.topics)
        names = sorted({c.topic for c in conns})
        several = len(names) > 1 or bag_name is not None
        if settings.mode == "csv" and several and not settings.fields:
            raise RostoolError("--csv prints one topic: name it (e.g. `rostool bag echo BAG /topic --csv`)")
        render = EchoRenderer(
            settings.mode,
            settings.fields,
            settings.noarr,
            settings.nostr,
            style="ros1" if reader.ros_version == 1 else "ros2",
            several=several,
        )
        prefix = ""
        if bag_name is not None:
            if settings.mode == "json":
                prefix = '{"bag": ' + dumps(bag_name) + ", "
            else:
                write(f"# bag: {path}\n")
        keep = _echo_filter(settings.expr)
        first = parse_time(settings.start, reader.start_ns, "start")
        last = parse_time(settings.end, reader.start_ns, "end")
        printed = 0
        for conn, timestamp, data in reader.messages(conns, first, last) if conns else ():
            msg = reader.deserialize(data, conn)
            if keep is not None and not keep(msg, conn.topic, timestamp):
                continue
            text = render.render(msg, timestamp, conn.topic)
            write((prefix + text[1:] if prefix else text) + "\n")
            printed += 1
            if settings.count is not None and printed >= settings.count:
                break


def _echo_many(items: Sequence[BagItem], settings: EchoSettings, jobs: int | None) -> None:
    """Each bag is printed into a file by a worker; the files are copied to stdout in the bags' order."""
    import shutil
    import tempfile
    from functools import partial

    from rostool.bag.many import successes

    with tempfile.TemporaryDirectory(prefix="rostool-echo-") as folder:
        work = partial(_echo_to_file, settings, folder)
        # no bar when the messages go to the same terminal: it would cut through them
        for _item, text_path in successes(work, items, jobs, "reading", bar=not sys.stdout.isatty()):
            with open(text_path, encoding="utf-8") as handle:
                shutil.copyfileobj(handle, sys.stdout)
            os.unlink(text_path)
        sys.stdout.flush()


def _echo_to_file(settings: EchoSettings, folder: str, item: BagItem) -> str:
    path = os.path.join(folder, f"{item.name}.txt")
    with open(path, "w", encoding="utf-8") as handle:
        _echo_bag(item.path, settings, handle.write, item.name)
    return path


def _echo_filter(expr: str | None) -> Callable[[object, str, int], bool] | None:
    if expr is None:
        return None
    from rostool.output.filter_expr import Bindings, compile_filter

    predicate = compile_filter(expr, names=("topic", "t"))

    def keep(msg: object, topic: str, timestamp: int) -> bool:
        return predicate(Bindings(msg, {"topic": topic, "t": timestamp / 1e9}))

    return keep


# -- convert / filter ----------------------------------------------------------------------------
FORMAT_OPTION = click.option(
    "--format",
    "fmt",
    type=click.Choice(["bag", "mcap", "db3"]),
    help="Output format when DST's name does not say (.bag, .mcap, .db3; other names: rosbag2 dir).",
)


@bag.command(context_settings=CONTEXT)
@click.argument("paths", nargs=-1, required=True, metavar="SRC... DST")
@FORMAT_OPTION
@click.option(
    "--topics", multiple=True, metavar="T", help="Only these topics (repeatable, or comma-separated)."
)
@click.option("--exclude-topics", multiple=True, metavar="T", help="Leave these topics out.")
@click.option("--start", metavar="S", help=f"Drop messages before: {TIME_HELP}.")
@click.option("--end", metavar="S", help=f"Drop messages after: {TIME_HELP}.")
@distro_option
@click.option("--force", is_flag=True, help="Replace DST if it is a bag (never an input, nor other files).")
@jobs_option
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

    if len(paths) < 2:
        raise RostoolError("give at least one SRC and a DST (e.g. `rostool bag convert in.bag out.mcap`)")
    selection = Selection(_topic_list(topics), _topic_list(exclude_topics), start, end)
    sources = paths[:-1]
    if _is_fleet(sources):
        job = _CopyJob(paths[-1], fmt, selection, None, distro, force, like_input=False)
        _copy_each(job, sources, jobs)
        return
    result = copy_bags(sources, paths[-1], fmt, selection, distro=distro, force=force)
    _report(result.written, len(result.topics), paths[-1])


@bag.command(name="filter", context_settings=CONTEXT)
@click.argument("paths", nargs=-1, required=True, metavar="IN... OUT")
@click.option(
    "--topics", multiple=True, metavar="T", help="Only these topics (repeatable, or comma-separated)."
)
@click.option("--start", metavar="S", help=f"Drop messages before: {TIME_HELP}.")
@click.option("--end", metavar="S", help=f"Drop messages after: {TIME_HELP}.")
@click.option("--filter", "expr", metavar="EXPR", help="Keep messages where EXPR holds (names: m, topic, t).")
@FORMAT_OPTION
@distro_option
@click.option("--force", is_flag=True, help="Replace OUT if it is a bag (never an input, nor other files).")
@jobs_option
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

    if len(paths) < 2:
        raise RostoolError("give IN and OUT (e.g. `rostool bag filter in.bag out.bag --topics /odom`)")
    sources, dst = paths[:-1], paths[-1]
    selection = Selection(_topic_list(topics), (), start, end)
    if len(sources) > 1 or _is_fleet(sources):
        _copy_each(_CopyJob(dst, fmt, selection, expr, distro, force, like_input=True), sources, jobs)
        return
    selection.predicate = _echo_filter(expr)
    result = copy_bags(sources, dst, fmt, selection, distro=distro, force=force, like_input=True)
    _report(result.written, len(result.topics), dst)


def _is_fleet(sources: Sequence[str]) -> bool:
    """A SRC that is a directory of bags (not itself a bag)."""
    from pathlib import Path

    from rostool.bag.many import is_one_bag

    return any(Path(src).is_dir() and not is_one_bag(Path(src)) for src in sources)


@dataclass(frozen=True)
class _CopyJob:
    """What convert/filter do to each bag of several (plain data: it goes to worker processes)."""

    out: str
    fmt: Any
    selection: Any
    expr: str | None
    distro: str
    force: bool
    like_input: bool


def _copy_each(job: _CopyJob, sources: Sequence[str], jobs: int | None) -> None:
    from functools import partial
    from pathlib import Path

    from rostool.bag.many import expand, successes

    items = expand(sources)
    try:
        Path(job.out).mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RostoolError(f"{job.out}: cannot create the output folder: {err.strerror or err}") from err
    done: list[tuple[BagItem, int, int, str]] = []
    try:
        for item, (written, topics, dst) in successes(partial(_copy_one, job), items, jobs, "copying"):
            done.append((item, written, topics, dst))
    finally:  # after the progress bar is gone
        for item, written, topics, dst in done:
            if dst:
                _report(written, topics, dst)
            else:
                click.echo(f"{item.path}: none of the --topics, nothing written", err=True)


def _present_topics(item: BagItem, job: _CopyJob) -> list[str]:
    from rostool.bag.reader import BagReader

    with BagReader([item.path], job.distro) as reader:
        return [name for name in job.selection.topics if name in reader.topics]


def _copy_one(job: _CopyJob, item: BagItem) -> tuple[int, int, str]:
    import dataclasses
    from pathlib import Path

    from rostool.bag.convert import copy_bags

    selection = dataclasses.replace(job.selection, predicate=_echo_filter(job.expr))
    if job.selection.topics:  # a fleet: not every bag has every topic
        selection.topics = _present_topics(item, job)
        if not selection.topics:
            return 0, 0, ""
    suffix = {"bag": ".bag", "mcap": ".mcap", "db3": ".db3"}.get(job.fmt or "", "")
    if job.fmt is None and job.like_input and item.path.is_file():
        suffix = item.path.suffix
    dst = str(Path(job.out) / f"{item.name}{suffix}")
    result = copy_bags(
        [item.path], dst, job.fmt, selection, distro=job.distro, force=job.force, progress=False,
        like_input=job.like_input,
    )  # fmt: skip
    return result.written, len(result.topics), dst


def _report(written: int, topics: int, dst: str) -> None:
    click.echo(f"wrote {written} messages on {topics} topics to {dst}", err=True)


# -- reindex -------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
@click.argument("files", nargs=-1, required=True, metavar="FILE...")
def reindex(files: tuple[str, ...]) -> None:
    """Rebuild the index of a ROS 1 .bag, the summary of an .mcap, or a rosbag2 directory cut short.

    Every message that reached the disk is kept, also those of a half-written last chunk. The original
    file is kept as NAME.orig.bag (NAME.orig.mcap), as `rosbag reindex` does. A rosbag2 directory left by
    a killed recorder (NAME.mcap.active/, NAME.db3.active/, or a `ros2 bag record` directory without
    metadata.yaml) gets its .mcap files repaired, its .db3 rolled back to the last commit and metadata.yaml
    rebuilt; the originals are kept in DIR.orig/.

    \b
    Examples:
      rostool bag reindex crashed.bag
      rostool bag reindex crashed.mcap
      rostool bag reindex run.mcap.active
    """
    from rostool.bag.reindex import reindex as rebuild

    for path in files:
        result = rebuild(path)
        extra = " (some from a half-written last chunk)" if result.partial else ""
        click.echo(
            f"{result.path}: {result.messages} messages indexed{extra}; original kept as {result.backup}"
        )


# -- play ----------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
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
@click.option(
    "--topics", multiple=True, metavar="T", help="Only these topics (repeatable, or comma-separated)."
)
@click.option("--clock", is_flag=True, help="Publish the bag time on /clock (rosgraph_msgs/Clock).")
@click.option("--hz", type=click.FloatRange(min=0, min_open=True), metavar="HZ",
              help="/clock messages per second (default 100; ROS 2: 40, as rosbag2).")  # fmt: skip
@click.option("-d", "--delay", type=click.FloatRange(min=0), default=0.2, show_default=True, metavar="S",
              help="Wait S seconds after advertising, so subscribers can connect.")  # fmt: skip
@click.option("--wait-for-subscribers", is_flag=True, help="Wait for a subscriber on every topic first.")
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
    On a terminal, a status line shows the bag time and space pauses/resumes ('s' steps while paused,
    't' toggles --pause-topics). Remappings may also be given as arguments (`/chatter:=/talk`), and with
    --topics (else --pause-topics), further topic names after the bags.

    \b
    Examples:
      rostool bag play run.bag
      rostool bag play -r 2 -s 10 -u 5 run.bag --topics /odom,/tf
      rostool bag play -l --clock run.bag /scan:=/scan_raw
      rostool bag play -p /replay --skip-empty 5 run.bag --pause-topics /goal
      rostool bag play talker.mcap
    """
    from rostool.bag.play import Console, Player, PlayOptions, parse_remaps
    from rostool.bag.reader import BagReader
    from rostool.commands._common import live_graph

    paths, remap_args, extra_topics = _play_arguments(args, bool(topics or pause_topics))
    extra_pause = [] if topics else extra_topics
    extra_topics = extra_topics if topics else []
    options = PlayOptions(
        rate=rate,
        start=start,
        duration=duration,
        loop=loop,
        topics=[*_topic_list(topics), *extra_topics],
        clock=clock,
        hz=hz or 100.0,  # rosbag's rate; a ROS 2 graph's default (rosbag2's) is set below
        delay=delay,
        remap=parse_remaps([*remap_args, *remap]),
        keep_alive=keep_alive,
        wait_for_subscribers=wait_for_subscribers,
        pause=pause,
        immediate=immediate,
        prefix=prefix,
        skip_empty=skip_empty,
        pause_topics=[*_topic_list(pause_topics), *extra_pause],
    )
    warn = (lambda text: None) if quiet else (lambda text: click.echo(f"rostool: warning: {text}", err=True))
    with BagReader(paths, distro) as reader, live_graph(ctx) as graph:
        console = Console.detect(quiet)
        if graph.encoding == "cdr":
            from rostool.bag.play_ros2 import Ros2Player

            options.hz = hz or 40.0
            player: Player = Ros2Player(reader, graph, options, console, warn)
        else:
            player = Player(reader, graph, options, console, warn)
        for flag, used in (("--pause", pause), ("--pause-topics", options.pause_topics)):
            if used and not console.keyboard:  # rosbag would stay paused forever
                raise RostoolError(f"{flag} needs a terminal on stdin to resume with space")
        with console:
            player.advertise()
            result = player.run()
            console.say("Done.")
    if result.published == 0 and not quiet:
        click.echo("rostool: warning: no message was played (check -s/-u and --topics)", err=True)


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


# -- record --------------------------------------------------------------------------------------
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


@bag.command(context_settings=CONTEXT)
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
@interfaces_option
@qos_options
@click.pass_context
def record(
    ctx: click.Context,
    topics: tuple[str, ...],
    all_topics: bool,
    regex: bool,
    exclude: str | None,
    output_name: str | None,
    output_prefix: str | None,
    duration: str | None,
    size: float | None,
    split: bool,
    max_splits: int | None,
    limit: int | None,
    node: str | None,
    fmt: Any,
    buffsize: int,
    compression: str | None,
    quiet: bool,
    force: bool,
    include_hidden_topics: bool,
    interface_paths: tuple[str, ...],
    qos: QosRequest,
) -> None:
    """Record topics of the live graph into a bag, until Ctrl+C (or --duration / --size).

    Messages are stored as received, with their publisher's type and definition and the receive time.
    The bag is written as NAME.bag.active and renamed when recording ends; Ctrl+C and SIGTERM always
    leave a complete, indexed bag (exit 0). After a crash or `kill -9`, `rostool bag reindex
    NAME.bag.active` recovers all but the last 0.1 s. .mcap/.db3 outputs are ROS 2 bags (types
    converted to pkg/msg/T). With -a or -e, topics that appear later are recorded too.

    These are rosbag record's flags (ROS 1); under ROS 2 (--ros2, ROS_VERSION=2) `bag record` takes ros2
    bag record's and writes a rosbag2 directory (see `rostool --ros2 bag record -h`).

    \b
    Examples:
      rostool bag record -a -O test.bag
      rostool bag record /odom /tf -o run             # run_2024-05-01-12-00-00.bag
      rostool bag record -e '/camera/.*' -x '.*compressed.*' --split --size 1024 --max-splits 5
      rostool bag record --node /move_base -l 100
      rostool bag record -a --duration 30s --format mcap
    """
    import threading

    from rostool.bag.record import Recorder, RecordOptions, stop_on_signals
    from rostool.commands._common import live_graph

    if output_name and output_prefix:
        raise RostoolError("choose one of -O (exact name) and -o (prefix)")
    if regex and not topics:
        raise RostoolError("-e needs at least one regular expression (e.g. `-e '/camera/.*'`)")
    options = RecordOptions(
        topics=topics,
        all_topics=all_topics,
        regex=regex,
        exclude=exclude,
        output_name=output_name,
        output_prefix=output_prefix,
        fmt=fmt,
        duration=_parse_duration(duration),
        size=None if size is None else int(size * 1024 * 1024),
        split=split,
        max_splits=max_splits,
        limit=limit,
        node=node,
        buffer_bytes=buffsize * 1024 * 1024,
        compression=compression or "none",
        force=force,
    )
    if compression and options.fmt not in (None, "bag"):
        raise RostoolError("--lz4/--bz2 compress ROS 1 .bag chunks; leave them out with --format mcap/db3")
    progress = None if quiet or not sys.stderr.isatty() else _RecordProgress()
    stop = threading.Event()
    with live_graph(ctx, interface_paths) as graph:
        graph.use_qos(qos)
        options.default_fmt = "mcap" if graph.encoding == "cdr" else "bag"

        def warn(text: str) -> None:
            if progress is not None:
                progress.end()
            click.echo(f"rostool: warning: {text}", err=True)

        recorder = Recorder(graph.record_source(warn, include_hidden_topics), options)
        with stop_on_signals(stop):
            try:
                result = recorder.run(stop, progress)
            finally:
                if progress is not None:
                    progress.end()
    for topic, count in sorted(result.dropped.items()):
        click.echo(
            f"rostool: warning: dropped {count} messages on {topic}: the disk could not keep up "
            "(raise -b/--buffsize)",
            err=True,
        )
    for topic, why in sorted(result.skipped.items()):
        click.echo(f"rostool: warning: some messages on {topic} were not written: {why}", err=True)
    if result.error is not None:
        kept = f"; what was recorded before is in {', '.join(map(str, result.files))}" if result.files else ""
        raise RostoolError(f"recording stopped: {result.error}{kept}")
    if not quiet:
        names = ", ".join(str(path) for path in result.files)
        topics = len(result.counts)
        removed = f" (--max-splits removed {len(result.removed)} older files)" if result.removed else ""
        click.echo(
            f"recorded {result.messages} messages on {topics} topic{'' if topics == 1 else 's'} to {names}"
            + removed,
            err=True,
        )


class _RecordProgress:
    """One status line on stderr, rewritten in place."""

    def __init__(self) -> None:
        self._last = 0.0
        self._shown = False

    def __call__(self, status: Any) -> None:
        from rostool.graph.rates import format_bytes

        dropped = f", {status.dropped} dropped" if status.dropped else ""
        sys.stderr.write(
            f"\r recording {status.path}: {status.messages} msgs on {status.topics} "
            f"topic{'' if status.topics == 1 else 's'}, "
            f"{format_bytes(status.bytes)}{dropped}    "
        )
        sys.stderr.flush()
        self._shown = True

    def end(self) -> None:
        if self._shown:
            sys.stderr.write("\n")
            sys.stderr.flush()
            self._shown = False
