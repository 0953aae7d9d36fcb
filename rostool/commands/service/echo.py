"""`rostool service echo`: ros2 service echo, the service's introspection events through `topic echo`."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, interfaces_option, json_option, ros_version
from rostool.errors import RostoolError


@click.command("echo")
@click.argument("name", metavar="SERVICE")
@click.option("-n", "count", type=click.IntRange(min=1), help="Stop after N events.")
@click.option("--once", is_flag=True, help="Stop after one event.")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), help="Give up after S seconds idle.")
@click.option("--csv", "as_csv", is_flag=True, help="Each event as a CSV row.")
@click.option("--no-arr", "noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--no-str", "nostr", is_flag=True, help="Show strings as their length.")
@click.option("-l", "--truncate-length", type=click.IntRange(min=0), help="Cut strings and arrays after N.")
@click.option("-f", "--full-length", is_flag=True, help="Never truncate.")
@click.option("--flow-style", is_flag=True, help="YAML in flow style.")
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def echo(ctx: click.Context, name: str, **options: Any) -> None:
    """ROS 2: print the introspection events of a service (its SERVICE/_service_event topic), as ros2
    service echo does: REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED. The service and
    its clients must have introspection on (configure_introspection), else nothing is published.

    \b
    Examples:
      rostool --ros2 service echo /add_two_ints
      rostool --ros2 service echo /add_two_ints --no-arr --once
    """
    from rostool.commands.topic.echo import echo as topic_echo

    if ros_version(ctx) == 1:
        raise RostoolError("service echo applies to ROS 2 graphs (ROS 1 services have no event topic)")
    event_topic = name.rstrip("/") + "/_service_event"
    ctx.invoke(topic_echo, name=event_topic, **options)
