"""`rostool topic`: list, info, type, find, echo, hz, bw, delay, pub (rostopic's forms)."""

from __future__ import annotations

import sys
import time
from typing import Any

import click

from rostool.commands._common import interfaces_option, json_option, live_graph, print_json
from rostool.commands._qos import qos_options
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest


@click.group()
def topic() -> None:
    """Inspect and use topics (like rostopic).

    \b
    Examples:
      rostool topic list -v
      rostool topic echo /hello_world -n 3
      rostool topic hz /hello_world
      rostool topic pub /chatter std_msgs/String "data: hi" -r 5
    """


@topic.command("list")
@click.option("-v", "--verbose", is_flag=True, help="Group by publishers/subscribers with types and counts.")
@click.option("-p", "publishers_only", is_flag=True, help="Only topics that have publishers.")
@click.option("-s", "subscribers_only", is_flag=True, help="Only topics that have subscribers.")
@json_option
@click.pass_context
def list_topics(
    ctx: click.Context, verbose: bool, publishers_only: bool, subscribers_only: bool, as_json: bool
) -> None:
    """List the topics of the live graph.

    \b
    Example:
      rostool topic list
    """
    with live_graph(ctx) as graph:
        topics = graph.topics()
    if publishers_only:
        topics = [t for t in topics if t.publishers]
    if subscribers_only:
        topics = [t for t in topics if t.subscribers]
    if as_json:
        print_json([vars(t) for t in topics])
        return
    if not verbose:
        for info in topics:
            click.echo(info.name)
        return
    if not subscribers_only:
        click.echo("\nPublished topics:")
        for t in (t for t in topics if t.publishers):
            count = len(t.publishers)
            click.echo(f" * {t.name} [{t.type}] {count} publisher{'s' if count > 1 else ''}")
    if not publishers_only:
        click.echo("\nSubscribed topics:")
        for t in (t for t in topics if t.subscribers):
            count = len(t.subscribers)
            click.echo(f" * {t.name} [{t.type}] {count} subscriber{'s' if count > 1 else ''}")
    click.echo("")


@topic.command("info")
@click.argument("name")
@click.option("-v", "--verbose", is_flag=True, help="ROS 2: every endpoint with its node, GID and QoS.")
@json_option
@click.pass_context
def info(ctx: click.Context, name: str, verbose: bool, as_json: bool) -> None:
    """Show a topic's type, publishers and subscribers.

    \b
    Example:
      rostool topic info /hello_world
    """
    with live_graph(ctx) as graph:
        resolved = graph.resolve(name)
        found = next((t for t in graph.topics() if t.name == resolved), None)
        if found is None:
            raise RostoolError(f"unknown topic {resolved}: no node publishes or subscribes to it")
        if graph.style == "ros2":
            _info_ros2(graph, found, verbose, as_json)
            return
        if verbose:
            raise RostoolError("topic info -v applies to ROS 2 graphs only")
        uris = {node: _node_uri(graph, node) for node in {*found.publishers, *found.subscribers}}
    if as_json:
        print_json({**vars(found), "uris": uris})
        return
    click.echo(f"Type: {found.type}\n")
    for title, nodes in (("Publishers", found.publishers), ("Subscribers", found.subscribers)):
        if nodes:
            click.echo(f"{title}: ")
            for node in nodes:
                click.echo(f" * {node} ({uris[node]})")
        else:
            click.echo(f"{title}: None")
        click.echo("")
    click.echo("")


def _info_ros2(graph: Any, found: Any, verbose: bool, as_json: bool) -> None:
    """ros2 topic info's form: type and counts, with -v every endpoint."""
    endpoints = graph.topic_endpoints(found.name)
    if as_json:
        print_json({**vars(found), "endpoints": endpoints})
        return
    lines = [f"Type: {found.type}"]
    for title, kind in (("Publisher", "PUBLISHER"), ("Subscription", "SUBSCRIPTION")):
        rows = [e for e in endpoints if e["endpoint_type"] == kind]
        lines += ["", f"{title} count: {len(rows)}"] if verbose else [f"{title} count: {len(rows)}"]
        for row in rows if verbose else []:
            namespace, _, node = row["node"].rpartition("/")
            qos = row["qos"]
            depth = {None: "UNKNOWN", 0: "KEEP_ALL"}.get(qos["depth"], f"KEEP_LAST ({qos['depth']})")
            lines += [
                "", f"Node name: {node}", f"Node namespace: {namespace or '/'}", f"Topic type: {row['type']}",
                f"Topic type hash: {row['type_hash'] or 'UNKNOWN'}", f"Endpoint type: {kind}",
                f"GID: {row['gid']}", "QoS profile:", f"  Reliability: {str(qos['reliability']).upper()}",
                f"  History (Depth): {depth}", f"  Durability: {str(qos['durability']).upper()}",
            ]  # fmt: skip
    click.echo("\n".join(lines))


def _node_uri(graph: Any, node: str) -> str:
    try:
        return str(graph.node_uri(node))
    except RostoolError:
        return "unknown"


@topic.command("type")
@click.argument("name")
@click.pass_context
def type_(ctx: click.Context, name: str) -> None:
    """Print only the type of a topic (for scripts).

    \b
    Example:
      rostool topic type /hello_world      # std_msgs/String
    """
    with live_graph(ctx) as graph:
        found = graph.topic_type(name)
    if found is None:
        raise RostoolError(f"unknown topic {name}: it has no publishers or subscribers")
    click.echo(found)


@topic.command("find")
@click.argument("type_name", metavar="TYPE")
@click.pass_context
def find(ctx: click.Context, type_name: str) -> None:
    """List the topics that carry messages of TYPE.

    \b
    Example:
      rostool topic find std_msgs/String
    """
    from rostool.interfaces.names import to_store_name

    with live_graph(ctx) as graph:
        for t in graph.topics():
            if t.type == type_name or (graph.style == "ros2" and t.type == to_store_name(type_name)):
                click.echo(t.name)


@topic.command("echo")
@click.argument("name")
@click.option("-n", "count", type=click.IntRange(min=1), help="Stop after N messages.")
@click.option("--once", is_flag=True, help="Stop after one message (same as -n 1).")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    help="Give up after S seconds with no message (exit 1).",
)
@click.option(
    "--field", "fields", multiple=True, help="Print only this field path (e.g. pose.position.x); repeatable."
)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per message.")
@click.option("--csv", "as_csv", is_flag=True, help="CSV rows, like rostopic echo -p.")
@click.option("--noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--nostr", is_flag=True, help="Show strings as their length.")
@click.option("--filter", "filter_text", help="Only messages where EXPR holds, e.g. \"m.data == 'go'\".")
@interfaces_option
@click.pass_context
@qos_options
def echo(
    ctx: click.Context,
    name: str,
    count: int | None,
    once: bool,
    timeout: float | None,
    fields: tuple[str, ...],
    as_json: bool,
    as_csv: bool,
    noarr: bool,
    nostr: bool,
    filter_text: str | None,
    interface_paths: tuple[str, ...],
    qos: QosRequest,
) -> None:
    """Print the messages of a topic (YAML like rostopic echo, or --json/--csv).

    \b
    Examples:
      rostool topic echo /hello_world -n 3
      rostool topic echo /odom --field pose.pose.position --json
      rostool topic echo /chatter --filter "m.data.startswith('Hello')"
    """
    from rostool.graph.inbox import Inbox
    from rostool.output.echo import EchoRenderer
    from rostool.output.filter_expr import compile_filter

    if as_json and as_csv:
        raise RostoolError("choose one of --json and --csv")
    keep = compile_filter(filter_text) if filter_text else None
    mode: Any = "json" if as_json else "csv" if as_csv else "yaml"
    limit = 1 if once else count
    out = sys.stdout
    interactive = out.isatty()
    with live_graph(ctx, interface_paths) as graph:
        graph.use_qos(qos)
        renderer = EchoRenderer(mode, fields, noarr, nostr, style=graph.style)
        if graph.topic_type(name) is None:
            click.echo(f"WARNING: topic [{name}] does not appear to be published yet", err=True)
        inbox = Inbox(graph, name)
        shown = 0
        for received in inbox.messages(timeout, on_idle=out.flush):
            try:
                message = received.decode()
            except RostoolError:
                raise
            except Exception as err:  # a peer sent bytes that do not match its own type
                raise RostoolError(f"cannot decode a {received.type_name} message on {name}: {err}") from err
            if keep is not None and not keep(message):
                continue
            out.write(renderer.render(message, received.recv_time_ns) + "\n")
            shown += 1
            if interactive:
                out.flush()
            if limit is not None and shown >= limit:
                break
        out.flush()


@topic.command("hz")
@click.argument("names", nargs=-1, required=True, metavar="TOPIC...")
@click.option("-w", "--window", type=click.IntRange(min=2), help="Average over the last N messages only.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per topic and report.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@click.pass_context
@qos_options
def hz(
    ctx: click.Context,
    names: tuple[str, ...],
    window: int | None,
    as_json: bool,
    duration: float | None,
    qos: QosRequest,
) -> None:
    """Measure the publishing rate of one or more topics (counts every message, never decodes).

    \b
    Examples:
      rostool topic hz /hello_world
      rostool topic hz /scan /odom -w 100
    """
    from rostool.graph.rates import RateMeter

    with live_graph(ctx) as graph:
        graph.use_qos(qos)
        meters = {graph.resolve(n): RateMeter(window) for n in names}
        for topic_name, meter in meters.items():
            if graph.topic_type(topic_name) is None:
                click.echo(f"WARNING: topic [{topic_name}] does not appear to be published yet", err=True)
            graph.subscribe(topic_name, _counter(meter), lambda e: click.echo(f"rostool: {e}", err=True))
            if not as_json:
                click.echo(f"subscribed to [{topic_name}]")
        _report_loop(meters, as_json, duration)


def _counter(meter: Any) -> Any:
    arrived, clock = meter.arrived, time.monotonic

    def on_message(_received: Any) -> None:
        arrived(clock())

    return on_message


def _report_loop(meters: dict[str, Any], as_json: bool, duration: float | None) -> None:
    started = time.monotonic()
    next_report = started + 1.0
    while duration is None or time.monotonic() - started < duration:
        time.sleep(max(0.0, min(next_report, started + (duration or 1e12)) - time.monotonic()))
        next_report += 1.0
        _print_rates(meters, as_json)


def _print_rates(meters: dict[str, Any], as_json: bool) -> None:
    rows = []
    for topic_name, meter in meters.items():
        summary = meter.summary()
        if summary is None:
            continue
        rate = 1.0 / summary.mean if summary.mean > 0 else 0.0
        rows.append((topic_name, rate, summary, meter.total))
    if as_json:
        for topic_name, rate, s, total in rows:
            print_json({"topic": topic_name, "rate": rate, "min": s.minimum, "max": s.maximum,
                        "std_dev": s.std_dev, "window": s.count + 1, "received": total})  # fmt: skip
        return
    if not rows:
        click.echo("no new messages")
        return
    if len(meters) == 1:
        _topic, rate, s, _total = rows[0]
        click.echo(
            f"average rate: {rate:.3f}\n\tmin: {s.minimum:.3f}s max: {s.maximum:.3f}s "
            f"std dev: {s.std_dev:.5f}s window: {s.count + 1}"
        )
        return
    header = ("topic", "rate", "min_delta", "max_delta", "std_dev", "window")
    table = [header] + [
        (t, f"{r:.4}", f"{s.minimum:.4}", f"{s.maximum:.4}", f"{s.std_dev:.4}", str(s.count + 1))
        for t, r, s, _ in rows
    ]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    lines = ["   ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) for row in table]
    lines.insert(1, "=" * len(lines[0]))
    click.echo("\n".join(lines))


@topic.command("bw")
@click.argument("name")
@click.option(
    "-w", "--window", type=click.IntRange(min=2), default=100, show_default=True, help="Messages averaged."
)
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@click.pass_context
@qos_options
def bw(ctx: click.Context, name: str, window: int, duration: float | None, qos: QosRequest) -> None:
    """Measure the bandwidth a topic uses (bytes of serialized messages per second).

    \b
    Example:
      rostool topic bw /camera/image_raw
    """
    from rostool.graph.rates import SizeMeter, format_bytes

    meter = SizeMeter(window)
    with live_graph(ctx) as graph:
        graph.use_qos(qos)
        graph.subscribe(name, lambda r: meter.arrived(time.monotonic(), len(r.payload)))
        click.echo(f"subscribed to [{name}]")
        started = time.monotonic()
        while duration is None or time.monotonic() - started < duration:
            time.sleep(1.0)
            result = meter.bandwidth(time.monotonic())
            if result is None:
                continue
            rate, s = result
            click.echo(
                f"average: {format_bytes(rate)}/s\n\tmean: {format_bytes(s.mean)} min: "
                f"{format_bytes(s.minimum)} max: {format_bytes(s.maximum)} window: {s.count}"
            )


@topic.command("delay")
@click.argument("name")
@click.option("-w", "--window", type=click.IntRange(min=1), help="Average over the last N messages only.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@click.pass_context
def delay(ctx: click.Context, name: str, window: int | None, duration: float | None) -> None:
    """Measure the delay between a message's header.stamp and its arrival.

    \b
    Example:
      rostool topic delay /scan
    """
    from rostool.graph.inbox import Inbox
    from rostool.graph.rates import RunningStats

    stats = RunningStats(window)
    with live_graph(ctx) as graph:
        inbox = Inbox(graph, name)
        click.echo(f"subscribed to [{name}]")
        started = next_report = time.monotonic()
        for received in inbox.messages():
            stamp = getattr(getattr(received.decode(), "header", None), "stamp", None)
            if stamp is None:
                raise RostoolError(f"messages on {name} have no header.stamp; delay needs one")
            stats.add(received.recv_time_ns / 1e9 - (stamp.sec + stamp.nanosec / 1e9))
            now = time.monotonic()
            if now >= next_report + 1.0:
                next_report = now
                s = stats.summary()
                if s is not None:
                    click.echo(
                        f"average delay: {s.mean:.3f}\n\tmin: {s.minimum:.3f}s max: {s.maximum:.3f}s "
                        f"std dev: {s.std_dev:.5f}s window: {s.count}"
                    )
            if duration is not None and now - started >= duration:
                break


@topic.command("pub")
@click.argument("name")
@click.argument("type_name", metavar="TYPE")
@click.argument("values", nargs=-1)
@click.option("-r", "--rate", type=click.FloatRange(min=0, min_open=True), help="Publish repeatedly at HZ.")
@click.option("-1", "--once", is_flag=True, help="Publish once, stay latched 3 s, then exit.")
@click.option("-l", "--latch", is_flag=True, help="Latch the last message for late subscribers.")
@click.option("-n", "--count", type=click.IntRange(min=1), help="With -r: stop after N messages.")
@click.option(
    "-f",
    "--file",
    "file",
    type=click.Path(exists=True, dir_okay=False),
    help="YAML messages separated by ---.",
)
@click.option("-q", "--quiet", is_flag=True, help="Print nothing.")
@interfaces_option
@click.pass_context
@qos_options
def pub(
    ctx: click.Context,
    name: str,
    type_name: str,
    values: tuple[str, ...],
    rate: float | None,
    once: bool,
    latch: bool,
    count: int | None,
    file: str | None,
    quiet: bool,
    interface_paths: tuple[str, ...],
    qos: QosRequest,
) -> None:
    """Publish a message given as YAML (missing fields get defaults).

    VALUES is one YAML mapping or the field values in order, as rostopic pub takes them. TYPE may be
    a custom type whose .msg file is in a source tree (--interfaces, ROS_PACKAGE_PATH, the workspace
    around the current directory): no build needed.

    \b
    Examples:
      rostool topic pub /chatter std_msgs/String "data: hi" -1
      rostool topic pub /cmd_vel geometry_msgs/Twist "{linear: {x: 0.5}}" -r 10
      rostool topic pub /point geometry_msgs/Point 1.0 2.0 3.0 -1
      rostool topic pub /status book_msgs/Status "{level: 2}" --interfaces ~/catkin_ws -1
    """
    from rostool.graph.publishing import publish_loop

    with live_graph(ctx, interface_paths) as graph:
        graph.use_qos(qos)
        publish_loop(
            graph, name, type_name, values, rate=rate, once=once, latch=latch, count=count,
            file=file, say=(lambda _t: None) if quiet else click.echo,
        )  # fmt: skip
