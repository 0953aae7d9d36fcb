"""`rostool bag echo`: print the messages of bags."""

from __future__ import annotations

import sys
from collections.abc import Sequence

import click

from rostool.commands.bag._options import CONTEXT, TIME_HELP, distro_option, jobs_option
from rostool.errors import RostoolError


@click.command(context_settings=CONTEXT)
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
    from rostool.bag.echo import EchoSettings, echo_bag, echo_many
    from rostool.bag.many import expand

    if as_json and as_csv:
        raise RostoolError("choose one of --json and --csv")
    paths, topics = _bags_then_topics(args)
    items = expand(paths)
    mode = "json" if as_json else "csv" if as_csv else "yaml"
    settings = EchoSettings(topics, count, mode, fields, noarr, nostr, expr, start, end, distro)
    if len(items) == 1:
        echo_bag(items[0].path, settings, sys.stdout.write, None)
        sys.stdout.flush()
        return
    if as_csv:
        raise RostoolError("--csv prints one bag: for several, use `rostool bag export --format csv`")
    echo_many(items, settings, jobs, sys.stdout)


def _bags_then_topics(args: Sequence[str]) -> tuple[list[str], tuple[str, ...]]:
    """The leading arguments that exist as paths are bags (at least the first), the rest topics."""
    from pathlib import Path

    count = 1
    while count < len(args) and Path(args[count]).exists():
        count += 1
    return list(args[:count]), tuple(args[count:])
