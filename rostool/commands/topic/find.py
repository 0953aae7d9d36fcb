"""`rostool topic find`: the topics of a type (rostopic find, ros2 topic find)."""

from __future__ import annotations

import click

from rostool.commands._common import echo_names, ignored_ros2_options, live_graph
from rostool.commands.topic._options import include_hidden_option


@click.command("find")
@click.argument("type_name", metavar="TYPE")
@click.option("-c", "--count-topics", is_flag=True, help="Only the number of topics found.")
@include_hidden_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def find(ctx: click.Context, type_name: str, count_topics: bool, include_hidden: bool) -> None:
    """List the topics that carry messages of TYPE.

    \b
    Example:
      rostool topic find std_msgs/String
    """
    from rostool.interfaces.names import hidden_name, to_store_name

    with live_graph(ctx) as graph:
        ros2 = graph.style == "ros2"
        found = [
            t.name for t in graph.topics()
            if (t.type == type_name or (ros2 and t.type == to_store_name(type_name)))
            and (include_hidden or not ros2 or not hidden_name(t.name))
        ]  # fmt: skip
    echo_names(found, count_topics)
