"""`rostool topic`: list, info, type, find, echo, hz, bw, delay, pub: rostopic's forms under ROS 1,
ros2 topic's under ROS 2 (the verbs choose by `graph.style`)."""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Callable
from typing import Any

import click

from rostool.commands._common import (
    ExtensibleGroup,
    ignored_ros2_options,
    interfaces_option,
    json_option,
    live_graph,
    print_json,
    ros_version,
)
from rostool.commands._qos import qos_options
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest


@click.group(cls=ExtensibleGroup, extra={"plot": "rostool.commands.topic_plot:plot"})
def topic() -> None:
    """Inspect and use topics (like rostopic, or ros2 topic).

    Flags and output follow the selected ROS version (--ros1/--ros2, ROS_VERSION, detection): rostopic's
    forms under ROS 1, ros2 topic's under ROS 2. rostool's extras (several --field, --json, --filter,
    --csv) work in both. ros2cli flags with no meaning here (--spin-time,
    -s/--use-sim-time) are accepted and ignored.

    \b
    Examples:
      rostool topic list -v
      rostool topic echo /hello_world -n 3
      rostool topic hz /hello_world
      rostool topic pub /chatter std_msgs/String "data: hi" -r 5
      rostool --ros2 topic list -t
      rostool --ros2 topic pub -t 3 /chatter std_msgs/msg/String "{data: hi}"
    """


include_hidden_option = click.option(
    "-a", "--include-hidden-topics", "--all", "include_hidden", is_flag=True,
    help="ROS 2: also hidden topics (a name part starting with _).",
)  # fmt: skip


@topic.command("list")
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
        return
    if as_json:
        print_json([vars(t) for t in topics])
        return
    if not verbose:
        for info in topics:
            click.echo(f"{info.name} [{info.type}]" if show_types and style == "ros2" else info.name)
        return
    lines = [] if style == "ros2" else [""]
    if not subscribers_only:
        lines.append("Published topics:")
        for t in (t for t in topics if t.publishers):
            count = len(t.publishers)
            lines.append(f" * {t.name} [{t.type}] {count} publisher{'s' if count > 1 else ''}")
        lines.append("")
    if not publishers_only:
        lines.append("Subscribed topics:")
        for t in (t for t in topics if t.subscribers):
            count = len(t.subscribers)
            lines.append(f" * {t.name} [{t.type}] {count} subscriber{'s' if count > 1 else ''}")
        lines.append("")
    click.echo("\n".join(lines))


@topic.command("info")
@click.argument("name")
@click.option("-v", "--verbose", is_flag=True, help="ROS 2: every endpoint with its node, GID and QoS.")
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
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
        if found is None and graph.style == "ros2":
            raise RostoolError(f"Unknown topic '{resolved}'")
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
    # ros2 prints each item (the type, a count, an endpoint's block) on its line(s), with -v each followed
    # by an empty line
    items = [f"Type: {found.type}"]
    for title, kind in (("Publisher", "PUBLISHER"), ("Subscription", "SUBSCRIPTION")):
        rows = [e for e in endpoints if e["endpoint_type"] == kind]
        items.append(f"{title} count: {len(rows)}")
        for row in rows if verbose else []:
            namespace, _, node = row["node"].rpartition("/")
            qos = row["qos"]
            depth = {None: "UNKNOWN", 0: "KEEP_ALL"}.get(qos["depth"], f"KEEP_LAST ({qos['depth']})")
            lines = [
                f"Node name: {node}", f"Node namespace: {namespace or '/'}", f"Topic type: {row['type']}",
                f"Topic type hash: {row['type_hash'] or 'UNKNOWN'}", f"Endpoint type: {kind}",
                f"GID: {row['gid']}", "QoS profile:", f"  Reliability: {str(qos['reliability']).upper()}",
                f"  History (Depth): {depth}", f"  Durability: {str(qos['durability']).upper()}",
                # discovery does not carry these to rostool; ROS 2's defaults are what nodes offer
                f"  Lifespan: {qos.get('lifespan', 'Infinite')}",
                f"  Deadline: {qos.get('deadline', 'Infinite')}",
                f"  Liveliness: {str(qos.get('liveliness', 'automatic')).upper()}",
                f"  Liveliness lease duration: {qos.get('liveliness_lease_duration', 'Infinite')}",
            ]  # fmt: skip
            items.append("\n".join(lines))
    click.echo("".join(f"{item}\n\n" for item in items) if verbose else "\n".join(items), nl=not verbose)


def _node_uri(graph: Any, node: str) -> str:
    try:
        return str(graph.node_uri(node))
    except RostoolError:
        return "unknown"


@topic.command("type")
@click.argument("name")
@include_hidden_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def type_(ctx: click.Context, name: str, include_hidden: bool) -> None:
    """Print only the type of a topic (for scripts).

    \b
    Example:
      rostool topic type /hello_world      # std_msgs/String
    """
    from rostool.interfaces.names import hidden_name

    with live_graph(ctx) as graph:
        found = graph.topic_type(name)
        if graph.style == "ros2" and not include_hidden and hidden_name(graph.resolve(name)):
            found = None
    if found is None:
        raise RostoolError(f"unknown topic {name}: it has no publishers or subscribers")
    click.echo(found)


@topic.command("find")
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
    click.echo(str(len(found)) if count_topics else "\n".join(found), nl=count_topics or bool(found))


@topic.command("echo")
@click.argument("name")
@click.argument("message_type", required=False, metavar="[TYPE]")
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
@click.option(
    "--csv", "as_csv", is_flag=True, help="CSV rows: rostopic echo -p's under ROS 1, ros2's under ROS 2."
)
@click.option("--noarr", "--no-arr", "noarr", is_flag=True, help="Show arrays as their type and length.")
@click.option("--nostr", "--no-str", "nostr", is_flag=True, help="Show strings as their length.")
@click.option("--filter", "filter_text", help="Only messages where EXPR holds, e.g. \"m.data == 'go'\".")
@click.option(
    "-l",
    "--truncate-length",
    type=click.IntRange(min=0),
    help="ROS 2: cut strings and arrays after N elements with '...' (default 128).",
)
@click.option("-f", "--full-length", is_flag=True, help="ROS 2: never truncate.")
@click.option("--flow-style", is_flag=True, help="ROS 2: YAML in flow style.")
@click.option("--raw", is_flag=True, help="ROS 2: the serialized bytes (CDR) of each message.")
@click.option(
    "-i",
    "--include-message-info",
    is_flag=True,
    help="ROS 2: before each message, what rostool knows of its arrival (received_timestamp).",
)
@click.option(
    "--no-lost-messages",
    "--lost-messages",
    "lost_messages",
    is_flag=True,
    help="Accepted and ignored (rostool does not report lost messages).",
)
@interfaces_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
@qos_options
def echo(
    ctx: click.Context,
    name: str,
    message_type: str | None,
    count: int | None,
    once: bool,
    timeout: float | None,
    fields: tuple[str, ...],
    as_json: bool,
    as_csv: bool,
    noarr: bool,
    nostr: bool,
    filter_text: str | None,
    truncate_length: int | None,
    full_length: bool,
    flow_style: bool,
    raw: bool,
    include_message_info: bool,
    lost_messages: bool,
    interface_paths: tuple[str, ...],
    qos: QosRequest,
) -> None:
    """Print the messages of a topic (YAML like rostopic echo or ros2 topic echo, or --json/--csv).

    TYPE (ROS 2 form, optional) names the message type; without it the publishers' type is used.

    \b
    Examples:
      rostool topic echo /hello_world -n 3
      rostool topic echo /odom --field pose.pose.position --json
      rostool topic echo /chatter --filter "m.data.startswith('Hello')"
      rostool --ros2 topic echo /chatter std_msgs/msg/String --once --no-str
    """
    from rostool.graph.inbox import Inbox
    from rostool.output.filter_expr import compile_filter

    if as_json and as_csv:
        raise RostoolError("choose one of --json and --csv")
    keep = compile_filter(filter_text) if filter_text else None
    limit = 1 if once else count
    out = sys.stdout
    interactive = out.isatty()
    with live_graph(ctx, interface_paths) as graph:
        graph.use_qos(qos)
        ros2 = graph.style == "ros2"
        ros2_only = {"--truncate-length": truncate_length is not None, "--full-length": full_length,
                     "--flow-style": flow_style, "--raw": raw, "--include-message-info": include_message_info,
                     "TYPE": message_type is not None}  # fmt: skip
        given = [flag for flag, used in ros2_only.items() if used]
        if given and not ros2:
            raise RostoolError(
                f"{', '.join(given)}: ros2 topic echo forms; under ROS 1 use rostopic's (--noarr, -n)"
            )
        render = _echo_renderer(graph, fields, as_json, as_csv, noarr, nostr, truncate_length, full_length,
                                flow_style, raw)  # fmt: skip
        if graph.topic_type(name) is None:
            # ros2 topic echo gives up here ("Could not determine the type"); rostool waits for a
            # publisher to tell it (or --timeout ends it), as it did since it could learn types
            click.echo(f"WARNING: topic [{name}] does not appear to be published yet", err=True)
        inbox = Inbox(graph, name)
        shown = 0
        for received in inbox.messages(timeout, on_idle=out.flush):
            message: Any = None
            if keep is not None or not raw:
                try:
                    message = received.decode()
                except RostoolError:
                    raise
                except Exception as err:  # a peer sent bytes that do not match its own type
                    raise RostoolError(
                        f"cannot decode a {received.type_name} message on {name}: {err}"
                    ) from err
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
        out.flush()


def _echo_renderer(
    graph: Any, fields: tuple[str, ...], as_json: bool, as_csv: bool, noarr: bool, nostr: bool,
    truncate_length: int | None, full_length: bool, flow_style: bool, raw: bool,
) -> Callable[[Any, Any], str]:  # fmt: skip
    """(received, decoded message) -> the text to print, in the style's form."""
    from rostool.output.echo import EchoRenderer

    if raw:
        return lambda received, _message: f"{bytes(received.payload)!r}\n---"
    mode: Any = "json" if as_json else "csv" if as_csv else "yaml"
    for path in fields if graph.style == "ros2" else ():
        if not path.strip(". "):
            raise RostoolError(f"Invalid field value '{path}'")
    if graph.style == "ros2" and not as_json:
        from rostool.output import ros2_echo

        store = getattr(getattr(graph, "types", None), "store", None)
        lookup = ros2_echo.fielddefs_lookup(getattr(store, "fielddefs", {}))
        opts = ros2_echo.Ros2EchoOptions(
            None if full_length else 128 if truncate_length is None else truncate_length,
            noarr,
            nostr,
            flow_style,
        )
        return functools.partial(_ros2_text, fields, as_csv, opts, lookup)
    renderer = EchoRenderer(mode, fields, noarr, nostr, style=graph.style)
    return lambda received, message: renderer.render(message, received.recv_time_ns)


def _ros2_text(
    fields: tuple[str, ...], as_csv: bool, opts: Any, lookup: Any, _received: Any, message: Any
) -> str:
    from rostool.output import ros2_echo
    from rostool.output.plain import select_field

    if not fields:
        if as_csv:
            return ros2_echo.to_csv(message, opts, lookup)
        return ros2_echo.to_yaml(message, opts, lookup) + "\n---"
    texts = []
    for path in fields:
        try:
            value = select_field(message, path)
        except LookupError as err:
            part = str(err).split("'")[1] if "'" in str(err) else path
            kind = type(message).__name__.split("__")[-1]
            raise RostoolError(f"Invalid field '{path}': '{kind}' object has no attribute '{part}'") from err
        texts.append(
            ros2_echo.to_csv(value, opts, lookup) if as_csv else ros2_echo.field_text(value, opts, lookup)
        )
    return ("," if as_csv else "\n").join(texts) + ("" if as_csv else "\n---")


@topic.command("hz")
@click.argument("names", nargs=-1, required=True, metavar="TOPIC...")
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
    """
    from rostool.graph.rates import RateMeter
    from rostool.output.filter_expr import compile_filter

    keep = compile_filter(filter_text) if filter_text else None
    with live_graph(ctx) as graph:
        graph.use_qos(qos)
        ros2 = graph.style == "ros2"
        meters = {graph.resolve(n): RateMeter(window) for n in names}
        for topic_name, meter in meters.items():
            if graph.topic_type(topic_name) is None:
                click.echo(f"WARNING: topic [{topic_name}] does not appear to be published yet", err=True)
            graph.subscribe(
                topic_name, _counter(meter, keep), lambda e: click.echo(f"rostool: {e}", err=True)
            )
            if as_json or (ros2 and len(meters) == 1):
                continue  # ros2 topic hz names the topics only when it measures several
            click.echo(f"{'Subscribed' if ros2 else 'subscribed'} to [{topic_name}]")
        _report_loop(meters, as_json, duration, graph.style)


def _counter(meter: Any, keep: Callable[[Any], bool] | None = None) -> Any:
    arrived, clock = meter.arrived, time.monotonic

    def on_message(received: Any) -> None:
        if keep is None or keep(received.decode()):
            arrived(clock())

    return on_message


def _report_loop(meters: dict[str, Any], as_json: bool, duration: float | None, style: str = "ros1") -> None:
    started = time.monotonic()
    next_report = started + 1.0
    printed: dict[str, int] = {}
    while duration is None or time.monotonic() - started < duration:
        time.sleep(max(0.0, min(next_report, started + (duration or 1e12)) - time.monotonic()))
        next_report += 1.0
        _print_rates(meters, as_json, style, printed)


def _print_rates(
    meters: dict[str, Any], as_json: bool, style: str = "ros1", printed: dict[str, int] | None = None
) -> None:
    """One report; `printed` (topic -> messages counted at its last report) leaves out topics that got
    nothing since: rostopic then says "no new messages", ros2 topic hz prints nothing."""
    printed = {} if printed is None else printed
    rows = []
    for topic_name, meter in meters.items():
        summary = meter.summary()
        if summary is None or printed.get(topic_name) == meter.total:
            continue
        printed[topic_name] = meter.total
        rate = 1.0 / summary.mean if summary.mean > 0 else 0.0
        rows.append((topic_name, rate, summary, meter.total))
    if as_json:
        for topic_name, rate, s, total in rows:
            print_json({"topic": topic_name, "rate": rate, "min": s.minimum, "max": s.maximum,
                        "std_dev": s.std_dev, "window": s.count + 1, "received": total})  # fmt: skip
        return
    if not rows:
        if style == "ros1":
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
    if style == "ros2":  # ros2 topic hz: fixed decimals, the header centred over its column
        cells = [(t, f"{r:.3f}", f"{s.minimum:.3f}", f"{s.maximum:.3f}", f"{s.std_dev:.5f}", str(s.count + 1))
                 for t, r, s, _ in rows]  # fmt: skip
        widths = [max(len(row[i]) for row in [header, *cells]) for i in range(len(header))]
        lines = ["   ".join(c.center(w) for c, w in zip(header, widths, strict=True))]
        lines += ["   ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) + " " for row in cells]
        lines.insert(1, "=" * len(lines[0]))
        click.echo("\n".join(lines))
        return
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
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
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
        ros2 = graph.style == "ros2"
        click.echo(f"{'Subscribed' if ros2 else 'subscribed'} to [{name}]")
        started = time.monotonic()
        while duration is None or time.monotonic() - started < duration:
            time.sleep(1.0)
            result = meter.bandwidth(time.monotonic())
            if result is None:
                continue
            rate, s = result
            if ros2:
                click.echo(_ros2_bandwidth(rate, s))
                continue
            click.echo(
                f"average: {format_bytes(rate)}/s\n\tmean: {format_bytes(s.mean)} min: "
                f"{format_bytes(s.minimum)} max: {format_bytes(s.maximum)} window: {s.count}"
            )


def _ros2_bandwidth(rate: float, s: Any) -> str:
    """ros2 topic bw's two lines: one unit for all four numbers, chosen by the rate."""
    scale, unit, digits = (1, "B", 0) if rate < 1000 else (1e3, "KB", 2) if rate < 1e6 else (1e6, "MB", 2)

    def show(value: float) -> str:
        return f"{value / scale:.{digits}f} {unit}"

    return (
        f"{show(rate)}/s from {s.count} messages\n"
        f"\tMessage size mean: {show(s.mean)} min: {show(s.minimum)} max: {show(s.maximum)}"
    )


@topic.command("delay")
@click.argument("name")
@click.option("-w", "--window", type=click.IntRange(min=1), help="Average over the last N messages only.")
@click.option("--duration", type=click.FloatRange(min=0, min_open=True), help="Stop after S seconds.")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
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
        if graph.style == "ros1":
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
@click.option(
    "-r",
    "--rate",
    type=click.FloatRange(min=0, min_open=True),
    help="Publish repeatedly at HZ (ROS 2: 1 Hz when not given).",
)
@click.option(
    "-1",
    "--once",
    is_flag=True,
    help="Publish once, then exit (ROS 1: stay latched 3 s first; ROS 2: after --keep-alive).",
)
@click.option("-l", "--latch", is_flag=True, help="Latch the last message for late subscribers.")
@click.option(
    "-n",
    "n_value",
    metavar="N|NAME",
    help="ROS 1: with -r, stop after N messages. ROS 2: --node-name (a number still means N messages).",
)
@click.option("--count", type=click.IntRange(min=1), help="With -r: stop after N messages.")
@click.option("--node-name", help="ROS 2: the name of the publishing node (default: rostool).")
@click.option(
    "-t", "--times", type=click.IntRange(min=1), help="ROS 2: publish N times at --rate, then exit."
)
@click.option(
    "-w",
    "--wait-matching-subscriptions",
    "wait_matching",
    type=click.IntRange(min=0),
    help="ROS 2: first wait for N matching subscriptions (default: the subscribers discovery shows, "
    "at most 3 s, with -1/-t).",
)
@click.option(
    "-m",
    "--max-wait-time-secs",
    "max_wait",
    type=click.FloatRange(min=0),
    help="ROS 2: wait at most S seconds for -w's subscriptions.",
)
@click.option(
    "--keep-alive",
    type=click.FloatRange(min=0),
    default=0.1,
    show_default=True,
    help="ROS 2: stay up S seconds after the last message.",
)
@click.option(
    "-p",
    "--print",
    "print_nth",
    type=click.IntRange(min=0),
    default=1,
    show_default=True,
    help="ROS 2: print every N-th message published (0: none).",
)
@click.option("--stdin", "from_stdin", is_flag=True, help="Read the message (YAML) from standard input.")
@click.option(
    "-f",
    "--file",
    "file",
    type=click.Path(exists=True, dir_okay=False),
    help="YAML messages separated by ---.",
)
@click.option("-q", "--quiet", is_flag=True, help="Print nothing.")
@interfaces_option
@ignored_ros2_options("spin_time", "use_sim_time")
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
    n_value: str | None,
    count: int | None,
    node_name: str | None,
    times: int | None,
    wait_matching: int | None,
    max_wait: float | None,
    keep_alive: float,
    print_nth: int,
    from_stdin: bool,
    file: str | None,
    quiet: bool,
    interface_paths: tuple[str, ...],
    qos: QosRequest,
) -> None:
    """Publish a message given as YAML (missing fields get defaults).

    VALUES is one YAML mapping or the field values in order, as rostopic pub takes them. TYPE may be
    a custom type whose .msg file is in a source tree (--interfaces, ROS_PACKAGE_PATH, the workspace
    around the current directory): no build needed. `stamp: now` sets a time to now; under ROS 2
    `header: auto` sets the header's stamp to now, as ros2 topic pub does.

    Under ROS 1 without -r the message is published once and latched (rostopic pub); under ROS 2 it is
    published at 1 Hz until -1/-t/Ctrl+C (ros2 topic pub), printing `publishing #N: ...`.

    \b
    Examples:
      rostool topic pub /chatter std_msgs/String "data: hi" -1
      rostool topic pub /cmd_vel geometry_msgs/Twist "{linear: {x: 0.5}}" -r 10
      rostool topic pub /point geometry_msgs/Point 1.0 2.0 3.0 -1
      rostool topic pub /status book_msgs/Status "{level: 2}" --interfaces ~/catkin_ws -1
      rostool --ros2 topic pub -t 5 -w 1 /chatter std_msgs/msg/String "{data: hi}"
    """
    from rostool.commands._common import open_live_graph
    from rostool.graph import select_ros_version
    from rostool.graph.publishing import publish_loop

    if n_value is not None:
        if n_value.isdigit() and int(n_value) >= 1:
            count = int(n_value)
        elif select_ros_version(ros_version(ctx)) == 2:
            node_name = n_value
        else:
            raise RostoolError(f"-n takes a number of messages (at least 1), not {n_value!r}")
    if from_stdin:
        values = (sys.stdin.read(),)
    graph = open_live_graph(ctx, interface_paths, node_name or "rostool")
    try:
        graph.use_qos(qos)
        say: Callable[[str], None] = (lambda _t: None) if quiet else click.echo
        if graph.style == "ros2" and not latch and not file:
            total = 1 if once else times if times is not None else count
            _publish_ros2(graph, name, type_name, values, rate or 1.0, total, wait_matching, max_wait,
                          keep_alive, 0 if quiet else print_nth)  # fmt: skip
            return
        publish_loop(
            graph, name, type_name, values, rate=rate, once=once, latch=latch, count=count or times,
            file=file, say=say,
        )  # fmt: skip
    finally:
        graph.close()


def _auto_values(value: Any) -> Any:
    """ros2 topic pub's `header: auto` (stamp now, empty frame) as rostool's `stamp: now`."""
    if isinstance(value, dict):
        return {
            k: {"stamp": "now"} if k == "header" and v == "auto" else _auto_values(v)
            for k, v in value.items()
        }
    if isinstance(value, list):
        return [_auto_values(v) for v in value]
    return value


def _publish_ros2(
    graph: Any, name: str, type_name: str, values: tuple[str, ...], rate: float, total: int | None,
    wait_matching: int | None, max_wait: float | None, keep_alive: float, print_nth: int,
) -> None:  # fmt: skip
    """ros2 topic pub's loop: wait for subscriptions, publish at `rate` (`total` times or until Ctrl+C)."""
    from rostool.graph.publishing import MATCH_WAIT_SECONDS
    from rostool.interfaces.values import message_args
    from rostool.output.repr_text import message_repr

    raw = _auto_values(message_args(values))
    text = repr(raw)
    rebuild = "now" in text  # a stamp of `now` is taken again for every message
    message = graph.build_message(type_name, raw)
    publisher = graph.publisher(name, type_name, latch=False)
    if wait_matching:
        deadline = None if max_wait is None else time.monotonic() + max_wait
        wait = 0.0
        while not publisher.wait_for_subscribers(wait_matching, wait):  # ros2's line, once a second
            if deadline is not None and time.monotonic() >= deadline:
                raise RostoolError(f"timed out waiting for {wait_matching} matching subscription(s)")
            click.echo(f"Waiting for at least {wait_matching} matching subscription(s)...")
            wait = 1.0
    elif total is not None:
        # a volatile subscriber gets nothing published before it matched: wait for the ones discovery shows
        try:
            wanted = len(next((t.subscribers for t in graph.topics() if t.name == publisher.topic), []))
        except RostoolError:
            wanted = 0
        publisher.wait_for_subscribers(wanted, MATCH_WAIT_SECONDS)
    if print_nth:
        click.echo("publisher: beginning loop")
    period = 1.0 / rate
    start = time.perf_counter()
    sent = 0
    while total is None or sent < total:
        delay = start + sent * period - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        if rebuild and sent:
            message = graph.build_message(type_name, raw)
        publisher.publish(message)
        sent += 1
        if print_nth and sent % print_nth == 0:
            click.echo(f"publishing #{sent}: {message_repr(message)}\n")
    time.sleep(keep_alive)
