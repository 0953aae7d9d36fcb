"""`rostool topic list`: rostopic list's forms (-v, -p, -s), ros2 topic list's (-t, -c, -a)."""

from __future__ import annotations

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.commands.topic._options import include_hidden_option
from rostool.graph.base import TopicInfo


@click.command("list")
@click.option("-v", "--verbose", is_flag=True, help="Group by publishers/subscribers with types and counts.")
@click.option("-p", "publishers_only", is_flag=True, help="Only topics that have publishers.")
@click.option(
    "-s",
    "subscribers_only",
    is_flag=True,
    help="ROS 1: only topics that have subscribers. ROS 2: --use-sim-time, accepted and ignored.",
)
@click.option("--use-sim-time", is_flag=True, hidden=True)
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: each topic with its type.")
@click.option("-c", "--count-topics", is_flag=True, help="Only the number of topics.")
@include_hidden_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time")
@click.pass_context
def list_topics(
    ctx: click.Context, verbose: bool, publishers_only: bool, subscribers_only: bool, use_sim_time: bool,
    show_types: bool, count_topics: bool, include_hidden: bool, as_json: bool,
) -> None:  # fmt: skip
    """List the topics of the live graph.

    \b
    Examples:
      rostool topic list
      rostool --ros2 topic list -t          # /chatter [std_msgs/msg/String]
      rostool --ros2 topic list -c -a
    """
    from rostool.interfaces.names import hidden_name

    with live_graph(ctx) as graph:
        topics = graph.topics()
        style = graph.style
    if style == "ros2":
        subscribers_only = False  # -s is --use-sim-time there
        if not include_hidden:
            topics = [t for t in topics if not hidden_name(t.name)]
    if publishers_only:
        topics = [t for t in topics if t.publishers]
    if subscribers_only:
        topics = [t for t in topics if t.subscribers]
    if count_topics:
        click.echo(str(len(topics)))
    elif as_json:
        print_json([vars(t) for t in topics])
    elif not verbose:
        for info in topics:
            click.echo(f"{info.name} [{info.type}]" if show_types and style == "ros2" else info.name)
    else:
        click.echo(_verbose_text(topics, publishers_only, subscribers_only, style == "ros2"))


def _verbose_text(topics: list[TopicInfo], publishers_only: bool, subscribers_only: bool, ros2: bool) -> str:
    """rostopic list -v's sections (ros2 topic list -v's without the leading empty line)."""
    lines = [] if ros2 else [""]
    sections = (("Published topics:", "publisher", subscribers_only), ("Subscribed topics:", "subscriber",
                publishers_only))  # fmt: skip
    for title, noun, skipped in sections:
        if skipped:
            continue
        lines.append(title)
        for t in topics:
            count = len(t.publishers if noun == "publisher" else t.subscribers)
            if count:
                lines.append(f" * {t.name} [{t.type}] {count} {noun}{'s' if count > 1 else ''}")
        lines.append("")
    return "\n".join(lines)
