"""One `bag record` for both forms: rosbag record's flags (record.py) and ros2 bag record's (record_ros2.py)
parse into a `RecordRequest`; `run_record` records it from the live graph and reports."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import click

from rostool.bag.record_options import RecordOptions, RecordResult
from rostool.bag.record_select import TopicSelector
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest

SNAPSHOT_WAIT = 10.0  # seconds the snapshot service waits for the snapshot to be written


@dataclass(frozen=True)
class RecordRequest:
    """What either form asks of the recorder, however its flags are spelled."""

    options: RecordOptions
    qos: QosRequest
    interface_paths: tuple[str, ...]
    include_hidden: bool  # subscribe to hidden topics (/_x) too
    quiet: bool
    form: Literal["rosbag", "ros2 bag"]  # whose messages: rosbag's or ros2 bag's
    selector: TopicSelector | None = None  # ros2 bag record's rules (they ask the graph for types)
    no_discovery: bool = False  # only the topics present at the start
    keyboard: bool = True  # space pauses and resumes when stdin is a terminal
    progress_every: float = 10.0  # seconds between progress lines when stderr is not a terminal (0: none)
    node_name: str = "rosbag2_recorder"  # ros2 bag record --node-name: its services are under it


def run_record(ctx: click.Context, request: RecordRequest) -> None:
    from rostool.bag.record_signals import stop_on_signals

    stop = threading.Event()
    # Ctrl+C sets `stop` from here on, while the recorder's modules import and the graph opens too: raised
    # there, a KeyboardInterrupt could land inside an import (leaving its module lock held for the writer
    # thread) or surface wrapped (a RuntimeError from `__set_name__`) where an `except Exception` takes it.
    with stop_on_signals(stop):
        _record(ctx, request, stop)


def _record(ctx: click.Context, request: RecordRequest, stop: threading.Event) -> None:
    from rostool.bag.player_services import Served, ServedLater, serve_recorder
    from rostool.bag.record import Recorder
    from rostool.commands._common import live_graph
    from rostool.commands.bag._record_console import PlainProgress, RecordDashboard, pause_controls

    ros2_form = request.form == "ros2 bag"
    progress: RecordDashboard | PlainProgress | None = None
    if not request.quiet:
        if sys.stderr.isatty():
            progress = RecordDashboard()
        elif request.progress_every > 0:
            progress = PlainProgress(request.progress_every)
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
            request.selector.freeze(source.topics_present())
        if ros2_form and not request.quiet and sys.stderr.isatty():  # piped: only warnings and the summary
            click.echo("[INFO] [rosbag2_recorder]: Listening for topics...", err=True)
            click.echo("[INFO] [rosbag2_recorder]: Recording...", err=True)

        def toggle() -> None:
            paused = recorder.toggle_paused()
            if progress is not None:
                progress.end()
            if not request.quiet:
                word = "Pausing" if paused else "Resuming"
                click.echo(f"[INFO] [rosbag2_recorder]: {word} recording." if ros2_form else
                           f"rostool: {word.lower()} recording", err=True)  # fmt: skip

        def snapshot() -> threading.Event:
            done = recorder.take_snapshot()
            if progress is not None:
                progress.end()
            if not request.quiet:
                click.echo("[INFO] [rosbag2_recorder]: Taking a snapshot." if ros2_form else
                           "rostool: writing a snapshot", err=True)  # fmt: skip
            return done

        take = snapshot if options.snapshot else None
        served: Served | ServedLater = Served()
        if ros2_form and graph.encoding == "cdr":  # rosbag2's recorder services, made beside the subscribing
            served = ServedLater(lambda: serve_recorder(
                graph, graph.resolve(request.node_name), lambda: recorder.paused, toggle,
                (lambda: snapshot().wait(SNAPSHOT_WAIT)) if take is not None else None,
                lambda: recorder.split().wait(SNAPSHOT_WAIT),
                warn if take is not None else lambda _text: None,  # said only where asked for (snapshots)
            ))  # fmt: skip
        with contextlib.closing(served), pause_controls(toggle, request.keyboard, take) as keys:
            if not request.quiet and (keys or recorder.paused):
                click.echo(_pause_hint(keys, recorder.paused, ros2_form), err=True)
            if not request.quiet and options.snapshot:
                click.echo(_snapshot_hint(keys, ros2_form), err=True)
            try:
                result = recorder.run(stop, progress)
                if isinstance(progress, RecordDashboard):
                    progress(recorder.status())  # the final counts
            finally:
                if progress is not None:
                    progress.end()
    _report(result, request, warn)


def _pause_hint(keys: bool, paused: bool, ros2_form: bool) -> str:
    """How to pause and resume (rosbag2's line under the ROS 2 form); SIGUSR1 where no keys are read."""
    how = "SPACE" if keys else f"SIGUSR1 (kill -USR1 {os.getpid()})"
    state = " Recording is paused." if paused else ""
    if ros2_form:
        return f"[INFO] [rosbag2_recorder]: Press {how} for pausing/resuming.{state}"
    return f"rostool: {how} pauses and resumes recording.{state}"


def _snapshot_hint(keys: bool, ros2_form: bool) -> str:
    how = ("'s' or " if keys else "") + f"SIGUSR2 (kill -USR2 {os.getpid()})"
    text = f"Snapshot mode: messages are held in memory and written when {how} asks for a snapshot."
    return f"[INFO] [rosbag2_recorder]: {text}" if ros2_form else f"rostool: {text}"


def _report(result: RecordResult, request: RecordRequest, warn: Callable[[str], None]) -> None:
    ros2_form = request.form == "ros2 bag"
    cache = "--max-cache-size" if ros2_form else "-b/--buffsize"
    for topic, count in sorted(result.dropped.items()):
        warn(f"dropped {count} messages on {topic}: the disk could not keep up (raise {cache})")
    for topic, why in sorted(result.skipped.items()):
        warn(f"some messages on {topic} were not written: {why}")
    for silence in result.silences:  # e.g. a Wi-Fi link that dropped: the bag is whole, but has a hole
        began = time.strftime("%H:%M:%S", time.localtime(silence.start_ns / 1e9))
        warn(f"heard nothing on {silence.topic} for {silence.seconds:.1f} s from {began} (a link or the "
             "publisher was down); the recording goes on either side")  # fmt: skip
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
