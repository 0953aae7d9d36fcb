"""`rostool topic bw`: the bandwidth a topic uses (rostopic bw's lines, ros2 topic bw's)."""

from __future__ import annotations

import time

import click

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.commands._qos import qos_options
from rostool.graph.qos import QosRequest


@click.command("bw")
@click.argument("name")
@click.option(
    "-w", "--window", type=click.IntRange(min=2), default=100, show_default=True, help="Messages averaged."
)
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
@qos_options
def bw(ctx: click.Context, name: str, window: int, duration: float | None, qos: QosRequest) -> None:
    """Measure the bandwidth a topic uses (bytes of serialized messages per second).

    \b
    Example:
      rostool topic bw /camera/image_raw
    """
    from rostool.graph.rates import SizeMeter
    from rostool.output.rate_text import bandwidth_text

    meter = SizeMeter(window)
    with live_graph(ctx) as graph:
        graph.use_qos(qos)
        graph.subscribe(name, lambda r: meter.arrived(time.monotonic(), len(r.payload)))
        click.echo(f"{'Subscribed' if graph.style == 'ros2' else 'subscribed'} to [{name}]")
        started = time.monotonic()
        while duration is None or time.monotonic() - started < duration:
            time.sleep(1.0)
            result = meter.bandwidth(time.monotonic())
            if result is not None:
                click.echo(bandwidth_text(*result, graph.style))
