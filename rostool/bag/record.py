"""`bag record`: subscribe to ROS 1 topics and write what arrives into bags, as `rosbag record` does.

Subscriptions are raw (md5 `*`): the bytes received are stored with the publisher's own type, md5sum and
definition from its connection header, stamped with the receive time. Network threads only append to a
byte-bounded queue; one writer thread empties it, so a slow disk never stalls a publisher (what does not
fit is counted as dropped and reported). ROS 1 bags are written by `ros1_writer.BagWriter` under
`NAME.bag.active` and renamed when closed; the data is pushed to the OS at least every 0.1 s, so after a
SIGKILL `rostool bag reindex NAME.bag.active` recovers everything but that last fraction of a second.
.mcap/.db3 outputs are ROS 2 bags (messages converted to CDR, types renamed `pkg/msg/T`), written by
rosbags under the directory `NAME.active/` and moved into place when closed; after a SIGKILL
`rostool bag reindex NAME.mcap.active` (or `.db3.active`) repairs that directory.
"""

from __future__ import annotations

import collections
import re
import sqlite3
import struct
import threading
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, cast

from rostool.bag.formats import FORMATS
from rostool.bag.record_options import (
    RecordOptions,
    RecordResult,
    RecordStatus,
    TopicStatus,
    check_target,
    output_format,
    target_name,
)
from rostool.bag.record_silence import SilenceWatch
from rostool.bag.record_sinks import Ros1Sink, Ros2Sink, Sink
from rostool.bag.rosbag2_dir import Rosbag2DirSink
from rostool.errors import RostoolError
from rostool.graph.recording import RecordSource, TypedRecordSource

_CLOCK = struct.Struct("<iI")  # builtin_interfaces/Time after the 4-byte CDR header
POLL_INTERVAL = 0.5  # how often the master is asked for new topics (-a, -e)
FLUSH_INTERVAL = 0.1  # the most a SIGKILL can lose, in seconds of messages


# -- the queue between network threads and the writer --------------------------------------------
class _Queue:
    """Byte-bounded: a message that does not fit is dropped and counted (per topic)."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.items: collections.deque[tuple[str, Any, int, bytes]] = collections.deque()
        self.bytes = 0
        self.dropped: collections.Counter[str] = collections.Counter()
        self.lock = threading.Lock()
        self.ready = threading.Event()
        self.accepting = True
        self.paused = False  # messages arriving while paused are not recorded (nor counted as dropped)
        self.periods: dict[str, int] = {}  # --max-rate: topic -> least ns between two kept messages
        self.last_kept: dict[str, int] = {}
        self.throttled: collections.Counter[str] = collections.Counter()
        self.clock: Callable[[], int | None] | None = None  # --use-sim-time: the latest /clock, if any

    def put(self, topic: str, payload: bytes, origin: Any) -> None:
        now = time.time_ns() if self.clock is None else self.clock()
        if not self.accepting or self.paused or now is None:
            return
        period = self.periods.get(topic)
        if period is not None:  # topic_tools throttle's rule: 1/HZ since the last message kept
            last = self.last_kept.get(topic)
            if last is not None and now - last < period:
                self.throttled[topic] += 1
                return
            self.last_kept[topic] = now
        size = len(payload)
        with self.lock:
            if self.bytes + size > self.limit:
                self.dropped[topic] += 1
                return
            self.bytes += size
        self.items.append((topic, origin, now, payload))
        if not self.ready.is_set():
            self.ready.set()

    def take(self) -> list[tuple[str, Any, int, bytes]]:
        items = self.items
        batch = []
        while items:
            batch.append(items.popleft())
        if batch:
            freed = sum(len(item[3]) for item in batch)
            with self.lock:
                self.bytes -= freed
        return batch


class _Ring:
    """Snapshot mode's buffer: the newest messages, at most `limit` bytes and `span_ns` of receive time."""

    def __init__(self, limit: int, span_ns: int) -> None:
        self.items: collections.deque[tuple[str, Any, int, bytes]] = collections.deque()
        self.bytes = 0
        self.limit = limit
        self.span_ns = span_ns

    def add(self, item: tuple[str, Any, int, bytes]) -> None:
        items = self.items
        items.append(item)
        self.bytes += len(item[3])
        while items and (self.bytes > self.limit or (self.span_ns and item[2] - items[0][2] > self.span_ns)):
            self.bytes -= len(items.popleft()[3])

    def take(self) -> list[tuple[str, Any, int, bytes]]:
        taken = list(self.items)
        self.items.clear()
        self.bytes = 0
        return taken


# -- the recorder --------------------------------------------------------------------------------
class Recorder:
    def __init__(self, source: RecordSource, options: RecordOptions) -> None:
        named = options.topics or options.static_topics
        if not named and not options.all_topics and options.node is None and options.wanted is None:
            raise RostoolError("no topics to record: name them, or use -a (all), -e REGEX or --node NODE")
        if options.split and options.size is None and options.duration is None:
            raise RostoolError("--split needs --size MB or --duration D")
        if options.max_splits is not None and not options.split:
            raise RostoolError("--max-splits needs --split")
        self.source = source
        self.options = options
        self.fmt = output_format(options)
        self.patterns = [_compile(p) for p in options.topics] if options.regex else []
        self.exclude = _compile(options.exclude) if options.exclude else None
        self.queue = _Queue(options.buffer_bytes)
        self.queue.paused = options.start_paused
        self.queue.periods = {source.resolve(t): round(1e9 / hz) for t, hz in options.max_rates.items()}
        self._written_bytes: collections.Counter[str] = collections.Counter()
        self._ring = (
            _Ring(options.buffer_bytes, round(options.snapshot_seconds * 1e9)) if options.snapshot else None
        )
        self._snapshot_asked = threading.Event()
        self._snapshot_waiters: list[threading.Event] = []  # set once the snapshot asked for is written
        self._split_waiters: list[threading.Event] = []  # set once the next file is started
        self.snapshots: list[int] = []  # messages written by each snapshot
        self.result = RecordResult()
        self.silences = SilenceWatch()
        self._subscribed: set[str] = set()
        self._split_index = 0 if options.split else None
        self._sink: Sink | None = None
        self._file_start: int | None = None
        self._failure: str | None = None
        self._limit_reached = threading.Event()
        self._stop = threading.Event()
        self._finishing = threading.Event()
        self._headers: dict[tuple[str, Any], tuple[object, dict[str, str]]] = {}
        self._opened = threading.Event()
        self._open_error: RostoolError | None = None
        self._written_in_file = 0
        self._subscribing = threading.Lock()  # subscribing vs closing the source
        self._closing = False
        self._discover_error: RostoolError | None = None
        self._static = _static_types(source, options.static_topics)  # checked before any file is made

    # -- files -----------------------------------------------------------------------------------
    def _open_next(self) -> Sink:
        layout = self.options.rosbag2
        if layout is not None:
            self._file_start = None
            self._written_in_file = 0
            return Rosbag2DirSink(layout, self.source, self.options.force)
        path = target_name(self.options, self.fmt, self._split_index)
        check_target(path, self.options.force)
        if self.fmt == "bag":
            sink: Sink = Ros1Sink(path, self.options.compression, self.options.force, self.source)
        else:
            sink = Ros2Sink(path, FORMATS[self.fmt], self.source, self.options.force,
                            storage_config=self.options.storage_config)  # fmt: skip
        self._file_start = None
        self._written_in_file = 0
        return sink

    def _rotate(self) -> None:
        assert self._sink is not None
        sink, self._sink = self._sink, None
        sink.close()
        self.result.skipped.update(sink.problems)
        self.result.files.append(sink.final)
        assert self._split_index is not None
        self._split_index += 1
        self._sink = self._open_next()
        keep = self.options.max_splits
        while keep is not None and len(self.result.files) >= keep:  # the new file counts too, as rosbag
            oldest = self.result.files.pop(0)
            oldest.unlink(missing_ok=True)
            self.result.removed.append(oldest)

    # -- subscribing -----------------------------------------------------------------------------
    def _wanted(self, topic: str) -> bool:
        if self.options.wanted is not None:
            return self.options.wanted(topic)
        if self.exclude is not None and self.exclude.fullmatch(topic):
            return False
        if self.options.all_topics:
            return True
        return any(p.fullmatch(topic) for p in self.patterns)

    def _subscribe(self, topic: str, type_name: str | None = None) -> None:
        with self._subscribing:
            if topic in self._subscribed or self._closing:
                return
            self._subscribed.add(topic)
            if type_name is None:
                self.source.subscribe(topic, self.queue.put)
            else:
                cast(TypedRecordSource, self.source).subscribe(topic, self.queue.put, type_name)

    def _discover_loop(self, stop: threading.Event) -> None:
        """-a/-e/--node: ask the master for topics every POLL_INTERVAL, on a thread of its own, so a master
        that hangs (stopped, overloaded) never holds up Ctrl+C."""
        while not stop.is_set() and not self._closing:
            try:
                self._discover()
            except RostoolError as err:
                self._discover_error = err
                stop.set()
                return
            stop.wait(POLL_INTERVAL)

    def _follow_clock(self) -> None:
        """--use-sim-time: stamp messages with the latest /clock (rosgraph_msgs/msg/Clock, CDR)."""
        latest: list[int] = []
        self.queue.clock = lambda: latest[0] if latest else None
        record_clock = "/clock" in self.options.topics or "/clock" in self._static or self._wanted("/clock")
        put = self.queue.put

        def on_clock(topic: str, payload: bytes, origin: Any) -> None:
            if len(payload) >= 12:
                sec, nanosec = _CLOCK.unpack_from(payload, 4)
                latest[:] = [sec * 1_000_000_000 + nanosec]
            if record_clock:
                put(topic, payload, origin)

        self._subscribed.add("/clock")
        self.source.subscribe("/clock", on_clock)

    def _discover(self) -> None:
        node = self.options.node
        if node is not None:
            found = self.source.subscribed_topics(self.source.resolve(node))
            wanted = [t for t in found if self.exclude is None or not self.exclude.fullmatch(t)]
        else:
            wanted = [t for t in self.source.published_topics() if self._wanted(t)]
        for topic in wanted:
            if topic not in self._subscribed:
                self._subscribe(topic)

    # -- writer thread ---------------------------------------------------------------------------
    def _write_loop(self) -> None:
        queue = self.queue
        last_flush = time.monotonic()
        try:
            while True:
                finishing = self._finishing.is_set()
                queue.ready.wait(FLUSH_INTERVAL)
                queue.ready.clear()
                batch = queue.take()
                ring = self._ring
                for item in batch:
                    if self._limit_reached.is_set():
                        break
                    if ring is not None:
                        ring.add(item)
                    else:
                        self._write_one(*item)
                if ring is not None and self._snapshot_asked.is_set():
                    self._snapshot_asked.clear()
                    waiters, self._snapshot_waiters = self._snapshot_waiters, []
                    taken = ring.take()
                    for item in taken:
                        self._write_one(*item)
                    self.snapshots.append(len(taken))
                    if self._sink is not None:
                        self._sink.flush()
                    for done in waiters:
                        done.set()
                if self._split_waiters:
                    self._split_now()
                now = time.monotonic()
                if self._sink is not None and (not batch or now - last_flush >= FLUSH_INTERVAL):
                    self._sink.flush()
                    last_flush = now
                if finishing and not batch:
                    return
        except OSError as err:
            self._failure = err.strerror or str(err)
        except RostoolError as err:
            self._failure = str(err)
        except sqlite3.Error as err:  # .db3 output: e.g. "database or disk is full"
            self._failure = str(err)
        except Exception as err:  # a bug of ours: still end with a closed, valid file and one line
            self._failure = f"internal error: {type(err).__name__}: {err}"
        self.queue.accepting = False

    def _write_one(self, topic: str, origin: Any, stamp: int, payload: bytes) -> None:
        known = self._headers.get((topic, origin))
        if known is None:
            fields = self.source.describe(topic, origin)
            known = self._headers[topic, origin] = (tuple(fields.values()), fields)
        key, fields = known
        options = self.options
        counts = self.result.counts
        if options.limit is not None and counts.get(topic, 0) >= options.limit:
            return
        if options.split and options.duration is not None and self._file_start is not None:
            limit = int(options.duration * 1e9)
            if stamp - self._file_start > limit:
                self._rotate()
        sink = self._sink
        if sink is None:
            return
        if self._file_start is None:
            self._file_start = stamp
        if sink.write(key, fields, stamp, payload):
            self.silences.heard(topic, stamp)
            counts[topic] = counts.get(topic, 0) + 1
            self._written_bytes[topic] += len(payload)
            self._written_in_file += 1
            if options.limit is not None and counts[topic] == options.limit:
                self._topic_done()
        if options.size is not None and sink.size >= options.size:
            if options.split:
                self._rotate()
            else:  # the size asked for: take nothing more and end the recording
                self.queue.accepting = False
                self._limit_reached.set()
                self._stop.set()

    def _topic_done(self) -> None:
        """--limit: rosbag ends the recording once every subscribed topic has its N messages."""
        limit = self.options.limit
        if all(self.result.counts.get(t, 0) >= (limit or 0) for t in tuple(self._subscribed)):
            self.queue.accepting = False
            self._limit_reached.set()
            self._stop.set()

    # -- main ------------------------------------------------------------------------------------
    def take_snapshot(self) -> threading.Event:
        """Snapshot mode: write what the buffer holds now (done by the writer thread); the event is set
        once it is written."""
        done = threading.Event()
        self._snapshot_waiters.append(done)
        self._snapshot_asked.set()
        self.queue.ready.set()
        return done

    def split(self) -> threading.Event:
        """A rosbag2 directory starts its next file now (done by the writer thread); the event is set once
        it has (at once for a single file, which cannot be split)."""
        done = threading.Event()
        if not isinstance(self._sink, Rosbag2DirSink):
            done.set()
            return done
        self._split_waiters.append(done)
        self.queue.ready.set()
        return done

    def _split_now(self) -> None:
        waiters, self._split_waiters = self._split_waiters, []
        if isinstance(self._sink, Rosbag2DirSink):
            self._sink.split()
        for done in waiters:
            done.set()

    @property
    def paused(self) -> bool:
        return self.queue.paused

    def toggle_paused(self) -> bool:
        """Pause or resume taking messages (space, SIGUSR1); the new state."""
        self.queue.paused = not self.queue.paused
        return self.queue.paused

    def status(self) -> RecordStatus:
        sink = self._sink
        return RecordStatus(
            path=sink.active if sink is not None else Path(),
            messages=self.result.messages,
            bytes=sink.size if sink is not None else 0,
            topics=len(self.result.counts),
            dropped=sum(self.queue.dropped.values()),
            paused=self.queue.paused,
            buffered=None if self._ring is None else len(self._ring.items),
            per_topic=self._per_topic(),
        )

    def _per_topic(self) -> dict[str, TopicStatus]:
        queue = self.queue
        counts = dict(self.result.counts)
        topics = sorted({*self._subscribed, *counts})
        if self.options.use_sim_time and "/clock" not in counts:  # followed for its time, not recorded
            topics.remove("/clock")
        return {
            t: TopicStatus(counts.get(t, 0), self._written_bytes[t], queue.dropped[t], queue.throttled[t])
            for t in topics
        }

    def run(
        self, stop: threading.Event, report: Callable[[RecordStatus], None] | None = None
    ) -> RecordResult:
        """Record until `stop` is set (or --duration/--size ends it, or a write fails)."""
        options = self.options
        self._stop = stop
        # The writer thread owns the files from opening to closing (sqlite connections are per thread).
        # Its modules are imported here first: an import it shared with this thread could wait on a module
        # lock that an interrupted import here left held.
        if self.fmt != "bag" or options.rosbag2 is not None:
            import rosbags.rosbag2  # noqa: F401
        writer = threading.Thread(target=self._writer_main, name="bag-writer", daemon=True)
        writer.start()
        # The bag is open before anything is subscribed: a message the recorder took is on disk within
        # FLUSH_INTERVAL (a chunk's second in .mcap), never held while the bag is still being made.
        self._opened.wait()
        if self._open_error is not None:
            writer.join()
            raise self._open_error
        try:
            if options.use_sim_time:
                self._follow_clock()
            for name, type_name in self._static.items():  # first: a topic also named or found takes its type
                self._subscribe(name, type_name)
            if not options.regex:
                for topic in options.topics:
                    name = self.source.resolve(topic)
                    if self.exclude is None or not self.exclude.fullmatch(name):
                        self._subscribe(name)
            discovering = bool(options.all_topics or options.regex or options.node or options.wanted)
            if discovering:  # the topics the source shows already (a daemon: all) count from the start
                self._discover()
            wait_ready = getattr(self.source, "wait_ready", None)
            if wait_ready is not None:  # ROS 2: --duration counts from when the subscriptions record
                wait_ready(stop=stop)
            started = time.monotonic()
            if discovering:
                threading.Thread(
                    target=self._discover_loop, args=(stop,), name="bag-discover", daemon=True
                ).start()
            while not stop.is_set():
                now = time.monotonic()
                if self._failure is not None or self._limit_reached.is_set() or not writer.is_alive():
                    break
                if options.duration is not None and not options.split and now - started >= options.duration:
                    break
                if report is not None:
                    report(self.status())
                wait = POLL_INTERVAL
                if options.duration is not None and not options.split:
                    wait = min(wait, max(0.0, started + options.duration - now))
                stop.wait(wait)
        finally:
            self.queue.accepting = False
            self._closing = True  # the discovery thread subscribes to nothing more
            if self._subscribing.acquire(timeout=0.5):  # unless a hung master holds it mid-subscribe
                self._subscribing.release()
            self.source.close()  # unregister now; nothing more arrives
            self._finishing.set()
            self.queue.ready.set()
            writer.join()
        if self._discover_error is not None:
            raise self._discover_error
        self.result.dropped = dict(self.queue.dropped)
        self.result.silences = list(self.silences.found)
        if self._failure is not None:
            self.result.error = self._failure
        return self.result

    def _writer_main(self) -> None:
        try:
            self._sink = self._open_next()
        except RostoolError as err:
            self._open_error = err
            return
        finally:
            self._opened.set()
        self._write_loop()
        self._close_last()

    def _close_last(self) -> None:
        sink, self._sink = self._sink, None
        if sink is None:
            return
        try:
            sink.close()
        except RostoolError as err:
            self._failure = str(err)
            return
        except (OSError, sqlite3.Error) as err:  # e.g. metadata.yaml of a rosbag2 directory
            reason = err.strerror if isinstance(err, OSError) and err.strerror else str(err)
            self._failure = (
                f"{sink.active}: cannot finish the bag: {reason}; free some space, then run "
                f"`rostool bag reindex {sink.active}`"
            )
            return
        finally:
            self.result.skipped.update(sink.problems)
        if self._written_in_file or not self.result.files:
            self.result.files.append(sink.final)
        else:
            sink.final.unlink()  # an empty last split file


def _static_types(source: RecordSource, static: Mapping[str, str]) -> dict[str, str]:
    """--static-topics-path: each topic's resolved name -> its type as the source's type store names it."""
    if not static:
        return {}
    if not isinstance(source, TypedRecordSource):
        raise RostoolError("static topics (a type given up front) are a ROS 2 recording mode")
    return {source.resolve(topic): source.known_type(type_name) for topic, type_name in static.items()}


def _compile(pattern: str) -> re.Pattern[str]:
    try:
        return re.compile(pattern)
    except re.error as err:
        raise RostoolError(f"bad regular expression {pattern!r}: {err}") from err
