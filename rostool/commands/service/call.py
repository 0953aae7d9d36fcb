"""`rostool service call`: rosservice call's form (VALUES, YAML response), ros2 service call's ([TYPE],
requester/response lines, -r)."""

from __future__ import annotations

import sys
import time

import click

from rostool.commands._common import (
    ignored_ros2_options,
    interfaces_option,
    json_option,
    live_graph,
    print_json,
)
from rostool.errors import RostoolError


@click.command("call", context_settings={"ignore_unknown_options": True})  # negative numbers are values
@click.argument("name", metavar="SERVICE")
@click.argument("values", nargs=-1)
@click.option("--wait", is_flag=True, help="Wait for the service to be advertised first.")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    help="Give up after S seconds (waiting, connecting and the call itself).",
)
@click.option("-r", "--rate", type=click.FloatRange(min=0, min_open=True), metavar="HZ",
              help="ROS 2: call again at HZ until Ctrl+C (as ros2 service call -r).")  # fmt: skip
@click.option("--stdin", "from_stdin", is_flag=True, help="Read the request (YAML) from standard input.")
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def call(
    ctx: click.Context,
    name: str,
    values: tuple[str, ...],
    wait: bool,
    timeout: float | None,
    rate: float | None,
    from_stdin: bool,
    interface_paths: tuple[str, ...],
    as_json: bool,
) -> None:
    """Call a service and print its response (YAML like rosservice, or --json).

    VALUES are the request fields in order, or one YAML mapping. The type is asked from the service
    and its .srv found in the sources (see --interfaces). On ROS 2, ros2 service call's form: an optional
    TYPE (pkg/srv/Name or pkg/Name; default: the type the server announces) before the values.

    \b
    Examples:
      rostool service call /sum_two_ints 7 8
      rostool service call /sum_two_ints "{a: 7, b: 8}"
      rostool service call /set_enabled true --wait --timeout 5
      rostool service call /reset
      rostool --ros2 service call /add_two_ints example_interfaces/srv/AddTwoInts "{a: 1, b: 2}"
      rostool --ros2 service call /add_two_ints "{a: 1, b: 2}" --json
      rostool --ros2 service call -r 1 /add_two_ints example_interfaces/srv/AddTwoInts "{a: 1, b: 2}"
    """
    from rostool.output.plain import to_plain
    from rostool.output.repr_text import message_repr
    from rostool.output.topic_echo import field_lookup
    from rostool.output.yaml_text import to_yaml

    if from_stdin:
        values = (*values, sys.stdin.read())
    with live_graph(ctx, interface_paths) as graph:
        if rate is not None and graph.style == "ros1":
            raise RostoolError("service call -r applies to ROS 2 graphs only (ros2 service call's form)")
        lookup = field_lookup(graph.types)
        while True:
            started = time.monotonic()
            request, response = graph.service_call(name, values, wait, timeout)
            if as_json:
                print_json(to_plain(response, graph.style))
            elif graph.style == "ros1":
                click.echo(to_yaml(response))
            else:
                click.echo(f"requester: making request: {message_repr(request, lookup)}\n")
                click.echo(f"response:\n{message_repr(response, lookup)}\n", nl=True)
            if rate is None:
                return
            time.sleep(max(0.0, 1.0 / rate - (time.monotonic() - started)))
