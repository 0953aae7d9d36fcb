"""`rostool topic bw`: bandwidth of topics (rostopic bw's lines, ros2 topic bw's; a table for several)."""

from __future__ import annotations

import time

import click

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.commands._qos import qos_options
from rostool.commands.topic._several import all_topics_option, chosen_topics, require_topics
from rostool.graph.qos import QosRequest


@click.command("bw")
@click.argument("names", nargs=-1, metavar="TOPIC...")
@all_topics_option
@click.option(
    "-w", "--window", type=click.IntRange(min=2), default=100, show_default=True, help="Messages averaged."
)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per topic and report.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
@qos_options
def bw(
    ctx: click.Context, names: tuple[str, ...], all_topics: bool, window: int, as_json: bool,
    duration: float | None, qos: QosRequest,
) -> None:  # fmt: skip
    """Measure the bandwidth topics use (bytes of serialized messages per second).

    One topic prints rostopic bw's (ros2 topic bw's) lines; several print a line per topic each second.

    \b
    Examples:
      rostool topic bw /camera/image_raw
      rostool topic bw /scan /odom
      rostool topic bw --all --duration 5
    """
    from rostool.graph.rates import SizeMeter, arrival_clock
    from rostool.output.rate_text import bandwidth_report

    require_topics(names, all_topics)
    with live_graph(ctx) as graph:
        graph.use_qos(qos)
        ros2 = graph.style == "ros2"
        meters = {topic: SizeMeter(window) for topic in chosen_topics(graph, names, all_topics)}
        arrival = arrival_clock()
        for topic_name, meter in meters.items():
            if len(meters) > 1 and graph.topic_type(topic_name) is None:
                click.echo(f"WARNING: topic [{topic_name}] does not appear to be published yet", err=True)
            graph.subscribe(
                topic_name,
                lambda r, meter=meter: meter.arrived(arrival(r), len(r.payload)),
                lambda e: click.echo(f"rostool: {e}", err=True),
            )
            if not as_json:
                click.echo(f"{'Subscribed' if ros2 else 'subscribed'} to [{topic_name}]")
        started = time.monotonic()
        next_report = started + 1.0
        while duration is None or time.monotonic() - started < duration:
            time.sleep(max(0.0, min(next_report, started + (duration or 1e12)) - time.monotonic()))
            next_report += 1.0
            now = time.monotonic()
            rows = [(t, *result) for t, m in meters.items() if (result := m.bandwidth(now)) is not None]
            for text in bandwidth_report(rows, len(meters) > 1, as_json, graph.style):
                click.echo(text)
