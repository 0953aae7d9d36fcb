"""`rostool bag`: info, echo, convert, filter, reindex over .bag, rosbag2 directories, .mcap and .db3.

Thin: parse options, call one function of `rostool.bag`, render. New verbs (play, record) are added
with `@bag.command()` like the ones below.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any

import click

from rostool.bag.typestores import DEFAULT_DISTRO, DISTROS
from rostool.errors import RostoolError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
TIME_HELP = "seconds since the epoch, or +S for S seconds after the bag's first message"


@click.group(context_settings=CONTEXT)
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


def _topic_list(values: Sequence[str]) -> list[str]:
    """`--topics /a --topics /b`, `--topics "/a /b"` and `--topics /a,/b` all work."""
    return [name for value in values for name in value.replace(",", " ").split()]


# -- info ----------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
@click.argument("bags", nargs=-1, required=True, metavar="BAG...")
@click.option("--json", "as_json", is_flag=True, help="One JSON object (a list for several bags).")
@click.option("--yaml", "as_yaml", is_flag=True, help="YAML with `rosbag info --yaml`'s keys.")
@click.option("--freq", is_flag=True, help="Also show each topic's rate (reads message timestamps).")
def info(bags: tuple[str, ...], as_json: bool, as_yaml: bool, freq: bool) -> None:
    """Summarize bags from their index: duration, size, counts, types and topics.

    \b
    Examples:
      rostool bag info run.bag
      rostool bag info rosbag2_dir/ --json | jq '.topics[] | select(.count > 0) | .name'
      rostool bag info a.bag b.mcap --yaml
    """
    from rostool.bag.info import bag_info, format_text, to_rosbag_yaml

    if as_json and as_yaml:
        raise RostoolError("choose one of --json and --yaml")
    infos = [bag_info(path, freq=freq) for path in bags]
    if as_json:
        from rostool.output.json_text import dumps

        click.echo(dumps(infos[0].to_dict() if len(infos) == 1 else [i.to_dict() for i in infos]))
    elif as_yaml:
        import yaml

        data = [to_rosbag_yaml(i) for i in infos]
        click.echo(yaml.safe_dump(data[0] if len(data) == 1 else data, sort_keys=False).rstrip("\n"))
    else:
        click.echo("\n\n".join(format_text(i) for i in infos))


# -- echo ----------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
@click.argument("bag_path", metavar="BAG")
@click.argument("topics", nargs=-1, metavar="[TOPIC]...")
@click.option("-n", "count", type=click.IntRange(min=1), help="Stop after N messages.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per line.")
@click.option("--csv", "as_csv", is_flag=True, help="CSV like `rostopic echo -p` (one topic).")
@click.option("--field", "fields", multiple=True, metavar="F", help="Print only this field (repeatable).")
@click.option("--noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--nostr", is_flag=True, help="Show strings as their length.")
@click.option("--filter", "expr", metavar="EXPR", help="Keep messages where EXPR holds (names: m, topic, t).")
@click.option("--start", metavar="S", help=f"First message time: {TIME_HELP}.")
@click.option("--end", metavar="S", help=f"Last message time: {TIME_HELP}.")
@distro_option
def echo(
    bag_path: str,
    topics: tuple[str, ...],
    count: int | None,
    as_json: bool,
    as_csv: bool,
    fields: tuple[str, ...],
    noarr: bool,
    nostr: bool,
    expr: str | None,
    start: str | None,
    end: str | None,
    distro: str,
) -> None:
    """Print the messages of a bag, as `rostopic echo -b` (ROS 1) or `ros2 topic echo` (ROS 2) would.

    Every YAML message ends with a `---` line. When more than one topic is printed (several TOPICs,
    or none given and the bag has several), each message is preceded by a comment line
    `# TOPIC @ SECONDS` (grep -A for it); with --json each line is then
    {"topic": ..., "t": seconds, "msg": {...}} instead of the bare message.

    \b
    Examples:
      rostool bag echo run.bag /turtle1/pose -n 2
      rostool bag echo run.bag /turtle1/pose --field x --csv
      rostool bag echo rosbag2_dir /chatter --json --filter 'm.data.startswith("hello")'
      rostool bag echo run.bag --filter 'topic == "/rosout" and m.level >= 4'
    """
    from rostool.bag.convert import parse_time
    from rostool.bag.reader import BagReader

    if as_json and as_csv:
        raise RostoolError("choose one of --json and --csv")
    with BagReader([bag_path], distro) as reader:
        conns = reader.select(topics)
        names = sorted({c.topic for c in conns})
        several = len(names) > 1
        if as_csv and several and not fields:
            raise RostoolError("--csv prints one topic: name it (e.g. `rostool bag echo BAG /topic --csv`)")
        render = _Renderer(
            style="ros1" if reader.ros_version == 1 else "ros2",
            as_json=as_json,
            as_csv=as_csv,
            fields=fields,
            noarr=noarr,
            nostr=nostr,
            several=several,
        )
        keep = _echo_filter(expr)
        first, last = parse_time(start, reader.start_ns, "start"), parse_time(end, reader.start_ns, "end")
        printed = 0
        write = sys.stdout.write
        for conn, timestamp, data in reader.messages(conns, first, last) if conns else ():
            msg = reader.deserialize(data, conn)
            if keep is not None and not keep(msg, conn.topic, timestamp):
                continue
            write(render(msg, conn.topic, timestamp))
            printed += 1
            if count is not None and printed >= count:
                break
        sys.stdout.flush()


def _echo_filter(expr: str | None) -> Callable[[object, str, int], bool] | None:
    if expr is None:
        return None
    from rostool.output.filter_expr import Bindings, compile_filter

    predicate = compile_filter(expr, names=("topic", "t"))

    def keep(msg: object, topic: str, timestamp: int) -> bool:
        return predicate(Bindings(msg, {"topic": topic, "t": timestamp / 1e9}))

    return keep


class _Renderer:
    """One message -> the text to print (YAML + `---`, a JSON line or a CSV row)."""

    def __init__(
        self,
        style: Any,
        as_json: bool,
        as_csv: bool,
        fields: Sequence[str],
        noarr: bool,
        nostr: bool,
        several: bool,
    ) -> None:
        from rostool.output.csv_text import CsvWriter

        self.style = style
        self.as_json = as_json
        self.as_csv = as_csv
        self.fields = list(fields)
        self.noarr, self.nostr = noarr, nostr
        self.several = several
        self.csv: dict[str, CsvWriter] = {}

    def _select(self, msg: object) -> object:
        from rostool.output.plain import select_field

        try:
            if len(self.fields) == 1:
                return select_field(msg, self.fields[0])
            return {name: select_field(msg, name) for name in self.fields}
        except LookupError as err:
            raise RostoolError(str(err.args[0]) if err.args else str(err)) from err

    def __call__(self, msg: object, topic: str, timestamp: int) -> str:
        from rostool.output.plain import elide

        if self.noarr or self.nostr:
            msg = elide(msg, self.noarr, self.nostr)
        value = self._select(msg) if self.fields else msg
        if self.as_json:
            return self._json(value, topic, timestamp)
        if self.as_csv:
            from rostool.output.csv_text import CsvWriter

            writer = self.csv.setdefault(topic, CsvWriter())
            return writer.row(value, timestamp) + "\n"
        text = self._yaml(value)
        if self.several:
            return f"# {topic} @ {timestamp // 1_000_000_000}.{timestamp % 1_000_000_000:09d}\n{text}\n---\n"
        return f"{text}\n---\n"

    def _yaml(self, value: object) -> str:
        from rostool.output.yaml_text import to_yaml, value_to_yaml

        if not self.fields:
            return to_yaml(value, self.style)
        if len(self.fields) == 1:
            return value_to_yaml(value, self.style)
        assert isinstance(value, dict)
        lines = []
        for name, item in value.items():
            text = value_to_yaml(item, self.style)
            if "\n" in text:
                text = "\n" + "\n".join("  " + line for line in text.splitlines())
            lines.append(f"{name}: {text}")
        return "\n".join(lines)

    def _json(self, value: object, topic: str, timestamp: int) -> str:
        from rostool.output.json_text import dumps
        from rostool.output.plain import to_plain

        if isinstance(value, dict) and self.fields:
            plain: Any = {name: to_plain(item, self.style) for name, item in value.items()}
        else:
            plain = to_plain(value, self.style)
        if self.several:
            plain = {"topic": topic, "t": timestamp / 1e9, "msg": plain}
        return dumps(plain) + "\n"


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
@click.option("--force", is_flag=True, help="Overwrite DST if it exists.")
def convert(
    paths: tuple[str, ...],
    fmt: Any,
    topics: tuple[str, ...],
    exclude_topics: tuple[str, ...],
    start: str | None,
    end: str | None,
    distro: str,
    force: bool,
) -> None:
    """Convert bags between ROS 1 .bag, .mcap, .db3 and rosbag2 directories.

    DST ending in .bag is a ROS 1 bag, in .mcap/.db3 a single self-describing storage file, anything
    else a rosbag2 directory (mcap storage unless --format db3). Message types and bytes are converted
    between ROS 1 and ROS 2 (tf/tfMessage becomes tf2_msgs/msg/TFMessage; other types keep their name
    and carry their definition). DST is written under a temporary name and appears only when complete.

    \b
    Examples:
      rostool bag convert run.bag run.mcap
      rostool bag convert rosbag2_dir/ run.bag --topics /tf,/odom
      rostool bag convert part1.bag part2.bag merged --format db3 --start +10 --end +20
    """
    from rostool.bag.convert import Selection, copy_bags

    if len(paths) < 2:
        raise RostoolError("give at least one SRC and a DST (e.g. `rostool bag convert in.bag out.mcap`)")
    selection = Selection(_topic_list(topics), _topic_list(exclude_topics), start, end)
    result = copy_bags(paths[:-1], paths[-1], fmt, selection, distro=distro, force=force)
    _report(result.written, len(result.topics), paths[-1])


@bag.command(name="filter", context_settings=CONTEXT)
@click.argument("src", metavar="IN")
@click.argument("dst", metavar="OUT")
@click.option(
    "--topics", multiple=True, metavar="T", help="Only these topics (repeatable, or comma-separated)."
)
@click.option("--start", metavar="S", help=f"Drop messages before: {TIME_HELP}.")
@click.option("--end", metavar="S", help=f"Drop messages after: {TIME_HELP}.")
@click.option("--filter", "expr", metavar="EXPR", help="Keep messages where EXPR holds (names: m, topic, t).")
@FORMAT_OPTION
@distro_option
@click.option("--force", is_flag=True, help="Overwrite OUT if it exists.")
def filter_(
    src: str,
    dst: str,
    topics: tuple[str, ...],
    start: str | None,
    end: str | None,
    expr: str | None,
    fmt: Any,
    distro: str,
    force: bool,
) -> None:
    """Copy the messages that match into a new bag (same format as IN unless OUT's name says otherwise).

    EXPR is a safe Python-like expression over the message `m`, its `topic` and its time `t` (seconds):
    field access, indexing, literals, comparisons, and/or/not, len/abs/min/max, string methods.

    \b
    Examples:
      rostool bag filter run.bag fast.bag --filter 'm.linear.x > 1.0' --topics /turtle1/cmd_vel
      rostool bag filter run.bag late.bag --filter 't > 1396293900'
      rostool bag filter rosbag2_dir out --filter 'topic != "/rosout"'
    """
    from rostool.bag.convert import Selection, copy_bags

    keep = _echo_filter(expr)
    selection = Selection(_topic_list(topics), (), start, end, keep)
    result = copy_bags([src], dst, fmt, selection, distro=distro, force=force, like_input=True)
    _report(result.written, len(result.topics), dst)


def _report(written: int, topics: int, dst: str) -> None:
    click.echo(f"wrote {written} messages on {topics} topics to {dst}", err=True)


# -- reindex -------------------------------------------------------------------------------------
@bag.command(context_settings=CONTEXT)
@click.argument("files", nargs=-1, required=True, metavar="FILE...")
def reindex(files: tuple[str, ...]) -> None:
    """Rebuild the index of a ROS 1 .bag (or the summary of an .mcap) whose writer was killed.

    Every message that reached the disk is kept, also those of a half-written last chunk. The original
    file is kept as NAME.orig.bag (NAME.orig.mcap), as `rosbag reindex` does.

    \b
    Examples:
      rostool bag reindex crashed.bag
      rostool bag reindex crashed.mcap
    """
    from rostool.bag.reindex import reindex as rebuild

    for path in files:
        result = rebuild(path)
        extra = " (some from a half-written last chunk)" if result.partial else ""
        click.echo(
            f"{result.path}: {result.messages} messages indexed{extra}; original kept as {result.backup}"
        )
