"""`rostool topic hz`: the publishing rate of topics (rostopic hz's lines, ros2 topic hz's table)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.commands._qos import qos_options
from rostool.commands.topic._several import all_topics_option, chosen_topics, require_topics
from rostool.graph.base import Received
from rostool.graph.qos import QosRequest


@click.command("hz")
@click.argument("names", nargs=-1, metavar="TOPIC...")
@all_topics_option
@click.option("-w", "--window", type=click.IntRange(min=2), help="Average over the last N messages only.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per topic and report.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@click.option("--filter", "filter_text", help="Only count messages where EXPR holds (decodes each message).")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time", "wall_time")
@click.pass_context
@qos_options
def hz(
    ctx: click.Context,
    names: tuple[str, ...],
    all_topics: bool,
    window: int | None,
    as_json: bool,
    duration: float | None,
    filter_text: str | None,
    qos: QosRequest,
) -> None:
    """Measure the publishing rate of one or more topics (counts every message, never decodes).

    \b
    Examples:
      rostool topic hz /hello_world
      rostool topic hz /scan /odom -w 100
      rostool topic hz --all --duration 5      # every published topic, a line each
    """
    from rostool.graph.rates import RateMeter, fresh_rates
    from rostool.output.filter_expr import compile_filter
    from rostool.output.rate_text import hz_report

    require_topics(names, all_topics)
    keep = compile_filter(filter_text) if filter_text else None
    with live_graph(ctx) as graph:
        graph.use_qos(qos)
        ros2 = graph.style == "ros2"
        meters = {topic: RateMeter(window) for topic in chosen_topics(graph, names, all_topics)}
        for topic_name, meter in meters.items():
            if graph.topic_type(topic_name) is None:
                click.echo(f"WARNING: topic [{topic_name}] does not appear to be published yet", err=True)
            graph.subscribe(
                topic_name, _counter(meter.arrived, keep), lambda e: click.echo(f"rostool: {e}", err=True)
            )
            if as_json or (ros2 and len(meters) == 1):
                continue  # ros2 topic hz names the topics only when it measures several
            click.echo(f"{'Subscribed' if ros2 else 'subscribed'} to [{topic_name}]")
        started = time.monotonic()
        next_report = started + 1.0
        printed: dict[str, int] = {}
        while duration is None or time.monotonic() - started < duration:
            time.sleep(max(0.0, min(next_report, started + (duration or 1e12)) - time.monotonic()))
            next_report += 1.0
            for text in hz_report(fresh_rates(meters, printed), len(meters) > 1, as_json, graph.style):
                click.echo(text)


def _counter(
    arrived: Callable[[float], None], keep: Callable[[Any], bool] | None
) -> Callable[[Received], None]:
    from rostool.graph.rates import arrival_clock

    arrival = arrival_clock()

    def on_message(received: Received) -> None:
        if keep is None or keep(received.decode()):
            arrived(arrival(received))

    return on_message
