"""One `bag record` for both forms: rosbag record's flags (record.py) and ros2 bag record's (record_ros2.py)
parse into a `RecordRequest`; `run_record` records it from the live graph and reports."""

from __future__ import annotations

import dataclasses
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import click

from rostool.bag.record_options import RecordOptions, RecordResult, RecordStatus
from rostool.bag.record_select import TopicSelector
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest


@dataclass(frozen=True)
class RecordRequest:
    """What either form asks of the recorder, however its flags are spelled."""

    options: RecordOptions
    qos: QosRequest
    interface_paths: tuple[str, ...]
    include_hidden: bool  # subscribe to hidden topics (/_x) too
    quiet: bool
    form: Literal["rosbag", "ros2 bag"]  # whose messages: rosbag's progress line or ros2 bag's log lines
    selector: TopicSelector | None = None  # ros2 bag record's rules (they ask the graph for types)
    no_discovery: bool = False  # only the topics present at the start


def run_record(ctx: click.Context, request: RecordRequest) -> None:
    from rostool.bag.record import Recorder, stop_on_signals
    from rostool.commands._common import live_graph

    ros2_form = request.form == "ros2 bag"
    progress = None if request.quiet or ros2_form or not sys.stderr.isatty() else _RecordProgress()
    stop = threading.Event()
    with live_graph(ctx, request.interface_paths) as graph:
        graph.use_qos(request.qos)
        options = dataclasses.replace(
            request.options, default_fmt="mcap" if graph.encoding == "cdr" else "bag"
        )
        if request.selector is not None:
            request.selector.graph = graph

        def warn(text: str) -> None:
            if progress is not None:
                progress.end()
            click.echo(f"rostool: warning: {text}", err=True)

        source = graph.record_source(warn, request.include_hidden)
        recorder = Recorder(source, options)
        if request.selector is not None and request.no_discovery:
            request.selector.freeze(source.published_topics())
        if ros2_form and not request.quiet and sys.stderr.isatty():  # piped: only warnings and the summary
            click.echo("[INFO] [rosbag2_recorder]: Listening for topics...", err=True)
            click.echo("[INFO] [rosbag2_recorder]: Recording...", err=True)
        with stop_on_signals(stop):
            try:
                result = recorder.run(stop, progress)
            finally:
                if progress is not None:
                    progress.end()
    _report(result, request, warn)


def _report(result: RecordResult, request: RecordRequest, warn: Callable[[str], None]) -> None:
    ros2_form = request.form == "ros2 bag"
    cache = "--max-cache-size" if ros2_form else "-b/--buffsize"
    for topic, count in sorted(result.dropped.items()):
        warn(f"dropped {count} messages on {topic}: the disk could not keep up (raise {cache})")
    for topic, why in sorted(result.skipped.items()):
        warn(f"some messages on {topic} were not written: {why}")
    if result.error is not None:
        kept = f"; what was recorded before is in {', '.join(map(str, result.files))}" if result.files else ""
        raise RostoolError(f"recording stopped: {result.error}{kept}")
    if request.quiet:
        return
    topics = len(result.counts)
    removed = result.removed and not ros2_form
    click.echo(
        f"recorded {result.messages} messages on {topics} topic{'' if topics == 1 else 's'} to "
        + ", ".join(str(path) for path in result.files)
        + (f" (--max-splits removed {len(result.removed)} older files)" if removed else ""),
        err=True,
    )


class _RecordProgress:
    """One status line on stderr, rewritten in place."""

    def __init__(self) -> None:
        self._last = 0.0
        self._shown = False

    def __call__(self, status: RecordStatus) -> None:
        from rostool.graph.rates import format_bytes

        dropped = f", {status.dropped} dropped" if status.dropped else ""
        sys.stderr.write(
            f"\r recording {status.path}: {status.messages} msgs on {status.topics} "
            f"topic{'' if status.topics == 1 else 's'}, "
            f"{format_bytes(status.bytes)}{dropped}    "
        )
        sys.stderr.flush()
        self._shown = True

    def end(self) -> None:
        if self._shown:
            sys.stderr.write("\n")
            sys.stderr.flush()
            self._shown = False
