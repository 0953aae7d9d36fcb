"""`rostool service echo`: ros2 service echo, the service's introspection events through `topic echo`."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, interfaces_option, json_option, ros_version
from rostool.errors import RostoolError


@click.command("echo")
@click.argument("name", metavar="SERVICE")
@click.argument("service_type", required=False, metavar="[SERVICE_TYPE]")
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
def echo(ctx: click.Context, name: str, service_type: str | None, **options: Any) -> None:
    """ROS 2: print the introspection events of a service (its SERVICE/_service_event topic), as ros2
    service echo does: REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED. The service and
    its clients must have introspection on (configure_introspection), else nothing is published.

    Any service type: its event type (pkg/srv/T_Event) is built from the .srv sources rostool finds, else
    learned from the service's node (its type description), as topic echo learns a type. SERVICE_TYPE
    (optional, as ros2 takes it) names the service's type.

    \b
    Examples:
      rostool --ros2 service echo /add_two_ints
      rostool --ros2 service echo /add_two_ints --no-arr --once
      rostool --ros2 service echo /set_flag std_srvs/srv/SetBool --flow-style
    """
    from rostool.commands.topic.echo import echo as topic_echo

    if ros_version(ctx) == 1:
        raise RostoolError("service echo applies to ROS 2 graphs (ROS 1 services have no event topic)")
    event_topic = name.rstrip("/") + "/_service_event"
    event_type = None if service_type is None else _event_type(service_type)
    ctx.invoke(topic_echo, name=event_topic, message_type=event_type, **options)


def _event_type(service_type: str) -> str:
    """`pkg/srv/Name` or `pkg/Name` -> the type of its events, `pkg/srv/Name_Event`; ros2's line otherwise."""
    parts = service_type.strip().strip("/").split("/")
    if len(parts) == 2:
        parts.insert(1, "srv")
    if len(parts) != 3 or parts[1] != "srv" or not all(part.isidentifier() for part in parts):
        raise RostoolError(f"The service type '{service_type}' is invalid")
    return "/".join(parts) + "_Event"
