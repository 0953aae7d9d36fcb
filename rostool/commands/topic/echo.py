"""`rostool topic echo`: rostopic echo's forms under ROS 1, ros2 topic echo's under ROS 2, and rostool's
--field/--json/--csv/--filter in both."""

from __future__ import annotations

import sys
from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, interfaces_option, live_graph
from rostool.commands._qos import topic_qos_options
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest

NO_TYPE = "Could not determine the type for the passed topic"  # ros2 topic echo's error, word for word


@click.command("echo")
@click.argument("name")
@click.argument("message_type", required=False, metavar="[TYPE]")
@click.option("-n", "count", type=click.IntRange(min=1), help="Stop after N messages.")
@click.option("--once", is_flag=True, help="Stop after one message (same as -n 1).")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True),
              help="Give up after S seconds with no message (exit 1).")  # fmt: skip
@click.option(
    "--field", "fields", multiple=True, help="Print only this field path (e.g. pose.position.x); repeatable."
)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per message.")
@click.option(
    "--csv", "as_csv", is_flag=True, help="CSV rows: rostopic echo -p's under ROS 1, ros2's under ROS 2."
)
@click.option("--noarr", "--no-arr", "noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--nostr", "--no-str", "nostr", is_flag=True, help="Show strings as their length.")
@click.option("--filter", "filter_text", help="Only messages where EXPR holds, e.g. \"m.data == 'go'\".")
@click.option("-l", "--truncate-length", type=click.IntRange(min=0),
              help="ROS 2: cut strings and arrays after N elements with '...' (default 128).")  # fmt: skip
@click.option("-f", "--full-length", is_flag=True, help="ROS 2: never truncate.")
@click.option("--flow-style", is_flag=True, help="ROS 2: YAML in flow style.")
@click.option("--raw", is_flag=True, help="ROS 2: the serialized bytes (CDR) of each message.")
@click.option("-i", "--include-message-info", is_flag=True, help="ROS 2: before each message, what rostool "
              "knows of its arrival (received_timestamp).")  # fmt: skip
@click.option("--no-lost-messages", "--lost-messages", "lost_messages", is_flag=True,
              help="Accepted and ignored (rostool does not report lost messages).")  # fmt: skip
@interfaces_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
@topic_qos_options
def echo(
    ctx: click.Context, name: str, message_type: str | None, count: int | None, once: bool,
    timeout: float | None, fields: tuple[str, ...], as_json: bool, as_csv: bool, noarr: bool, nostr: bool,
    filter_text: str | None, truncate_length: int | None, full_length: bool, flow_style: bool, raw: bool,
    include_message_info: bool, lost_messages: bool, interface_paths: tuple[str, ...], qos: QosRequest,
) -> None:  # fmt: skip
    """Print the messages of a topic (YAML like rostopic echo or ros2 topic echo, or --json/--csv).

    TYPE (ROS 2 form, optional) names the message type; without it the publishers' type is used.

    \b
    Examples:
      rostool topic echo /hello_world -n 3
      rostool topic echo /odom --field pose.pose.position --json
      rostool topic echo /chatter --filter "m.data.startswith('Hello')"
      rostool --ros2 topic echo /chatter std_msgs/msg/String --once --no-str
    """
    from rostool.graph.inbox import Inbox, decoded
    from rostool.output.filter_expr import compile_filter
    from rostool.output.topic_echo import EchoForm, echo_renderer

    if as_json and as_csv:
        raise RostoolError("choose one of --json and --csv")
    keep = compile_filter(filter_text) if filter_text else None
    limit = 1 if once else count
    out = sys.stdout
    interactive = out.isatty()
    with live_graph(ctx, interface_paths) as graph:
        graph.use_qos(qos)
        ros2_only = {"--truncate-length": truncate_length is not None, "--full-length": full_length,
                     "--flow-style": flow_style, "--raw": raw, "--include-message-info": include_message_info,
                     "TYPE": message_type is not None}  # fmt: skip
        given = [flag for flag, used in ros2_only.items() if used]
        if given and graph.style != "ros2":
            raise RostoolError(
                f"{', '.join(given)}: ros2 topic echo forms; under ROS 1 use rostopic's (--noarr, -n)"
            )
        form = EchoForm(fields, as_json, as_csv, noarr, nostr, truncate_length, full_length, flow_style, raw)
        render = echo_renderer(graph.style, graph.types, form)
        unknown = message_type is None and graph.topic_type(name) is None  # ros2 looks only without TYPE
        if unknown and timeout is None:
            # ros2 topic echo gives up here ("Could not determine the type"); rostool waits for a
            # publisher to tell it, as it did since it could learn types
            click.echo(f"WARNING: topic [{name}] does not appear to be published yet", err=True)
        inbox = Inbox(graph, name)
        shown = 0
        try:
            for received in inbox.messages(timeout, on_idle=out.flush):
                message: Any = None
                if keep is not None or not raw:
                    message = decoded(received, name)
                if keep is not None and not keep(message):
                    continue
                if include_message_info:
                    info = {"received_timestamp": received.recv_time_ns}
                    out.write(f"---Got new message, message info:---\n{info}\n")
                out.write(render(received, message) + "\n")
                shown += 1
                if interactive:
                    out.flush()
                if limit is not None and shown >= limit:
                    break
        except RostoolError:
            if unknown and graph.topic_type(name) is None:  # --timeout ran out before any publisher came
                click.echo(NO_TYPE, err=True)  # ros2's one line and exit status
                ctx.exit(1)
            raise
        out.flush()
