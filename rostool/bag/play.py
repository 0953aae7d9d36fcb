"""`bag play`: publish the messages of bags into the live ROS 1 graph on their recorded schedule.

ROS 1 bags are published byte for byte, with the type name, md5sum and definition stored in the bag and
latched when the recording publisher was. ROS 2 bags (.mcap, .db3, rosbag2 directories) are converted
from CDR to ROS 1 bytes (rosbags' `cdr_to_ros1`) and published with the built-in ROS 1 type of the same
name (`pkg/msg/T` -> `pkg/T`); the first message of each topic is checked against the ROS 1 type. Topics
whose type has no ROS 1 equivalent (e.g. rcl_interfaces/msg/Log) are skipped with a warning; when no
topic is left, that is an error.

--clock publishes the bag time on /clock at --hz while playing, and the stamp of every message played.
`play_ros2.Ros2Player` plays into ROS 2 graphs on this schedule: it replaces `_plan` (how a connection is
published) and the clock message.

As rosbag does: --prefix is prepended to each bag topic before remapping (`-p /pre` with
`/pre/chatter:=/talk`); --skip-empty jumps the schedule, status line and /clock over a gap longer than
SEC to the next message; --pause-topics (bag topic names) pauses before publishing a message on one of
them, until space ('t' toggles this). With --immediate, neither skips nor pauses apply.

Pause, rate, next message, burst, seek and stop are `play_controls.PlayControls`' (keys and rosbag2's
control services alike). Timing: see `schedule.py` (absolute due times, no drift). The playback origin is
the first message played (after -s), as rosbag's view begins at its first message: a pass never starts
with a dead wait.
"""

from __future__ import annotations

import re
import struct
import time
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from rosbags.interfaces import Connection, ConnectionExtRosbag1, ConnectionExtRosbag2

from rostool.bag.play_console import Console, split_keys
from rostool.bag.play_controls import Burst, PlayControls
from rostool.bag.reader import BagReader
from rostool.bag.schedule import PlayClock, sleep_until
from rostool.errors import RostoolError
from rostool.graph.base import Graph
from rostool.graph.publishing import MATCH_WAIT_SECONDS, match_known_subscribers, unmatched_warning
from rostool.interfaces.names import to_ros1_name
from rostool.interfaces.ros1 import Ros1Type, builtin_store

if TYPE_CHECKING:
    from rostool.bag.player_services import Controls

_CLOCK = struct.Struct("<II")
# rosbag2's key help, as `ros2 bag play` logs it ('s' and 't' work too)
ROS2_KEYS = (("SPACE", "Pause/Resume"), ("CURSOR_RIGHT", "Play Next Message"),
             ("CURSOR_UP", "Increase Rate 10%"), ("CURSOR_DOWN", "Decrease Rate 10%"))  # fmt: skip
UI_INTERVAL = 0.05  # keyboard polling and status line refresh, seconds


@dataclass
class PlayOptions:
    rate: float = 1.0
    start: float = 0.0  # seconds into the bag
    duration: float | None = None  # seconds of bag time
    loop: bool = False
    topics: Sequence[str] = ()
    clock: bool = False
    hz: float = 100.0
    delay: float = 0.2  # seconds between advertising and the first message
    remap: Mapping[str, str] = field(default_factory=dict)
    keep_alive: bool = False
    wait_for_subscribers: bool = False
    match_wait: float = MATCH_WAIT_SECONDS  # for the subscribers the graph shows, before the first message
    pause: bool = False  # start paused (space resumes)
    immediate: bool = False  # no waiting between messages
    prefix: str = ""  # prepended to every bag topic, before remapping
    skip_empty: float | None = None  # seconds: longer gaps between messages are skipped
    pause_topics: Sequence[str] = ()  # bag topics: pause before publishing a message on them
    # ros2 bag play's filters and end
    exclude: Sequence[str] = ()  # bag topics not to play
    regex: str | None = None  # play only topics whose name contains a match
    exclude_regex: str | None = None  # leave out topics whose name contains a match
    until: float | None = None  # bag time (seconds since the epoch) where playing ends
    clock_topics: Sequence[str] = ()  # bag topics whose messages' times are also published on /clock
    clock_topics_all: bool = False  # every message's time is published on /clock
    max_messages: int | None = None  # bag burst: stop after this many messages (None: all)


@dataclass
class PlayResult:
    published: int = 0
    loops: int = 0
    skipped: dict[str, str] = field(default_factory=dict)  # topic -> why


class RawPublisher(Protocol):
    """What playing needs of a publisher (a ROS 1 one, or a ROS 2 DDS writer in play_ros2)."""

    def publish_raw(self, payload: bytes) -> None: ...
    def wait_for_subscribers(self, count: int, timeout: float) -> bool: ...


@dataclass
class _Kind:
    """How one bag connection's messages go out: what identifies the type on a topic, and how."""

    key: str  # two connections may share a topic only with the same key (md5sum, or ROS 2 type name)
    label: str  # the type, for messages
    advertise: Callable[[str], RawPublisher]  # topic -> publisher
    convert: Callable[[Any], Any] | None = None
    verify: Callable[[Any], object] | None = None


@dataclass
class _Plan:
    topic: str  # where it is published (after remapping)
    publisher: RawPublisher
    convert: Callable[[Any], Any] | None  # bytes of the bag's ROS version -> the graph's
    # Decodes a converted message with the graph's own type; dropped once the first one passed.
    verify: Callable[[Any], object] | None = None
    pause: bool = False  # a --pause-topics topic
    clock: bool = False  # publish this message's time on /clock (ros2 bag play --clock-topics)


def parse_remaps(values: Collection[str]) -> dict[str, str]:
    """`/from:=/to` pairs (rosbag and ROS remapping syntax); the player resolves the names."""
    remaps = {}
    for value in values:
        source, sep, target = value.partition(":=")
        if not sep or not source or not target:
            raise RostoolError(f"bad remapping {value!r}: expected FROM:=TO, e.g. /chatter:=/talk")
        remaps[source] = target
    return remaps


class Player(PlayControls):
    graph_name = "ROS 1"  # in messages about what cannot be played
    clock_per_message = True  # /clock also carries every played message's stamp, besides the --hz ticks

    def __init__(
        self,
        reader: BagReader,
        graph: Graph,
        options: PlayOptions,
        console: Console | None = None,
        warn: Callable[[str], None] | None = None,
    ) -> None:
        self.reader = reader
        self.graph = graph
        self.types = graph.types
        self.options = options
        self.console = console or Console(False, False)
        self.warn = warn or (lambda text: None)
        self.clock = PlayClock(options.rate)
        self.result = PlayResult()
        self._plans: dict[int, _Plan] = {}
        self._publishers: dict[str, tuple[RawPublisher, str]] = {}  # topic -> (publisher, md5 or type)
        self._clock_pub: RawPublisher | None = None
        self._next_tick = 0.0
        self._next_ui = 0.0
        self._burst: Burst | None = None
        self._seek_to: int | None = None
        self._stopping = False
        self.controls: Controls | None = None
        self._started = False
        self.total = (reader.end_ns - reader.start_ns) / 1e9 if reader.message_count else 0.0
        self.window = self._window()
        self.connections = self._select()
        self.remap = {graph.resolve(name): graph.resolve(to) for name, to in options.remap.items()}
        self.pause_topics = self._pause_topics()
        self._pause_for_topics = bool(self.pause_topics)  # 't' toggles it
        self._skip_ns = None if options.skip_empty is None else round(options.skip_empty * 1e9)

    def _pause_topics(self) -> frozenset[str]:
        names = frozenset(self.graph.resolve(t) for t in self.options.pause_topics)
        unknown = sorted(names - {c.topic for c in self.connections})
        if unknown:
            raise RostoolError(
                f"--pause-topics {', '.join(unknown)}: not played from the bag "
                "(name the bag's topic, before --prefix and --remap)"
            )
        return names

    def _select(self) -> list[Connection]:
        options, resolve = self.options, self.graph.resolve
        conns = self.reader.select(
            [resolve(t) for t in options.topics], [resolve(t) for t in options.exclude]
        )
        for pattern, keep in ((options.regex, True), (options.exclude_regex, False)):
            if pattern:
                try:
                    compiled = re.compile(pattern)
                except re.error as err:
                    raise RostoolError(f"bad regular expression {pattern!r}: {err}") from err
                conns = [c for c in conns if bool(compiled.search(c.topic)) == keep]
        return conns

    def _window(self) -> tuple[int, int | None]:
        start = self.reader.start_ns + round(self.options.start * 1e9)
        end = None if self.options.duration is None else start + round(self.options.duration * 1e9)
        if self.options.until is not None:
            until = round(self.options.until * 1e9)
            end = until if end is None else min(end, until)
        return start, end

    # -- advertising -----------------------------------------------------------------------------
    def advertise(self) -> None:
        """One publisher per topic; skip (and warn about) what cannot be played in this graph."""
        for conn in self.connections:
            self._plan(conn)
        if not self._plans:
            if self.result.skipped:
                reasons = "; ".join(f"{t}: {why}" for t, why in sorted(self.result.skipped.items()))
                raise RostoolError(f"nothing to play in {self.graph_name}: {reasons}")
            return
        for topic, why in self.result.skipped.items():  # only now: no warning before that error
            self.warn(f"skipping {topic}: {why}")
        if self.options.clock or self.options.clock_topics or self.options.clock_topics_all:
            self._clock_pub = self._advertise_clock()

    def _plan(self, conn: Connection) -> None:
        """Plan how `conn`'s messages are published, or skip its topic."""
        options = self.options
        topic = self.graph.resolve(options.prefix + conn.topic) if options.prefix else conn.topic
        topic = self.remap.get(topic, topic)  # rosbag remaps the prefixed name
        try:
            kind = self._kind_of(conn)
        except RostoolError as err:
            self._skip(conn.topic, str(err), warn=False)
            return
        existing = self._publishers.get(topic)
        if existing is not None:
            publisher, key = existing
            if key != kind.key:
                self._skip(conn.topic, f"a second type {kind.label} on {topic}", warn=False)
                return
        else:
            publisher = kind.advertise(topic)
            self._publishers[topic] = (publisher, kind.key)
        pause = conn.topic in self.pause_topics
        clock = options.clock_topics_all or conn.topic in options.clock_topics
        self._plans[id(conn)] = _Plan(topic, publisher, kind.convert, kind.verify, pause, clock)

    def _kind_of(self, conn: Connection) -> _Kind:
        msg_type, convert, latch = self._type_of(conn)
        return _Kind(
            key=msg_type.md5sum,
            label=msg_type.name,
            advertise=lambda topic: self.graph.raw_publisher(topic, msg_type, latch),
            convert=convert,
            verify=None if convert is None else msg_type.deserialize,
        )

    def _advertise_clock(self) -> RawPublisher:
        return self.graph.raw_publisher("/clock", self.types.builtin("rosgraph_msgs/Clock"))

    def _clock_message(self, stamp: int) -> bytes:
        """A rosgraph_msgs/Clock message of the graph's ROS version for bag time `stamp` (ns)."""
        return _CLOCK.pack(*divmod(stamp, 1_000_000_000))

    def _skip(self, topic: str, why: str, warn: bool = True) -> None:
        if topic not in self.result.skipped:
            self.result.skipped[topic] = why
            if warn:
                self.warn(f"skipping {topic}: {why}")

    def _type_of(self, conn: Connection) -> tuple[Ros1Type, Callable[[Any], Any] | None, bool]:
        name = to_ros1_name(conn.msgtype)
        if isinstance(conn.ext, ConnectionExtRosbag1):
            md5, definition = conn.digest, conn.msgdef.data
            try:
                store = self.types.resolve(name, md5, definition).store
            except RostoolError:
                store = builtin_store()  # raw bytes are published as stored; decoding is never needed
            return Ros1Type(name, md5, definition, store), None, bool(conn.ext.latching)
        if "/msg/" not in conn.msgtype or not self.types.has_builtin(name):
            raise RostoolError(f"{conn.msgtype} has no ROS 1 equivalent")
        resolver = self.reader.resolver
        if conn.msgtype in resolver.unknown:
            raise RostoolError(resolver.missing_message(conn.msgtype))
        msgtype = conn.msgtype

        def convert(raw: Any) -> Any:
            return resolver.store.cdr_to_ros1(raw, msgtype)

        latch = False
        if isinstance(conn.ext, ConnectionExtRosbag2):
            latch = any(q.durability.value == 1 for q in conn.ext.offered_qos_profiles)
        return self.types.builtin(name), convert, latch

    # -- playing ---------------------------------------------------------------------------------
    def run(self) -> PlayResult:
        if not self._plans:
            return self.result
        try:
            if self.options.pause:
                self.clock.pause(time.perf_counter())
            self._pause_before_start()
            while not self._stopping:
                published = self._play_once()
                self.result.loops += 1
                if not self.options.loop or published == 0:
                    break
            while self.options.keep_alive and not self._stopping:
                now = time.perf_counter()
                self._ui(now)
                self._tick_clock(now)
                time.sleep(UI_INTERVAL)
        finally:
            self.close_controls()
        return self.result

    def _pause_before_start(self) -> None:
        options = self.options
        if options.delay > 0:
            self.console.say(f"Waiting {options.delay:g} seconds after advertising topics...")
            time.sleep(options.delay)
        if options.wait_for_subscribers:
            self.console.say("Waiting for a subscriber on every topic...")
            for publisher, _md5 in self._publishers.values():
                while not publisher.wait_for_subscribers(1, 0.1):
                    self._commands(time.perf_counter())
        publishers = {topic: publisher for topic, (publisher, _key) in self._publishers.items()}
        unmatched = match_known_subscribers(self.graph, publishers, options.match_wait)
        if unmatched:
            self.warn(unmatched_warning(unmatched, options.match_wait))
        if not self.console.keyboard:
            self.console.say("")
        elif self.console.form == "ros2 bag":
            for key, action in ROS2_KEYS:
                self.console.say(f"[INFO] [rosbag2_player]: Press {key} for {action}")
        else:
            self.console.say("Hit space to toggle paused, or 's' to step.")

    def _messages(self, start: int) -> Iterator[tuple[_Plan, int, Any]]:
        end = self.window[1]
        plans = self._plans
        conns = [c for c in self.connections if id(c) in plans]
        for conn, stamp, data in self.reader.messages(conns, start, end):
            plan = plans[id(conn)]
            if plan.convert is None:
                yield plan, stamp, data
                continue
            try:
                payload = plan.convert(data)
                if plan.verify is not None:
                    plan.verify(payload)
                    plan.verify = None
            except Exception:
                if plan.verify is not None:
                    self._skip(conn.topic, f"{conn.msgtype} is laid out differently in {self.graph_name}")
                    del plans[id(conn)]
                continue
            yield plan, stamp, payload

    def _play_once(self) -> int:
        """One pass over the bag (again from where a seek asks); the messages published."""
        published = 0
        start = self.window[0]
        while True:
            published += self._play_from(start, published)
            if self._seek_to is None or self._stopping:
                break
            start, self._seek_to = self._seek_to, None
            self.clock.start(start, time.perf_counter())  # paused or not, as before the seek
        self.result.published += published
        return published

    def _play_from(self, start: int, before: int) -> int:
        published = 0
        clock_pub = self._clock_pub
        wait = self._wait
        limit = self.options.max_messages
        for plan, stamp, payload in self._messages(start):
            if limit is not None and self.result.published + before + published >= limit:
                break
            if before + published == 0:
                now = time.perf_counter()
                self.clock.start(stamp, now)
                self._next_tick = now
                self._started = True
            wait(stamp, plan.pause)
            if self._seek_to is not None or self._stopping:
                break
            if clock_pub is not None:
                if self.clock_per_message or plan.clock:
                    clock_pub.publish_raw(self._clock_message(stamp))
                elif self.options.clock:
                    self._tick_clock(time.perf_counter())  # behind schedule, _wait returns before ticking
            plan.publisher.publish_raw(payload)
            published += 1
            burst = self._burst
            if burst is not None and burst.sent():
                burst.reply()
                self._burst = None
        return published

    def _wait(self, stamp: int, pause_topic: bool = False) -> None:
        clock = self.clock
        if self._burst is not None:
            clock.start(stamp, time.perf_counter())  # stay paused, at this message's time
            return
        if self.options.immediate and not clock.paused:
            now = time.perf_counter()
            if now < self._next_ui:
                return
            self._ui(now)  # keys and services between messages too
            if not clock.paused or self._seek_to is not None or self._stopping:
                return
        clock_pub = self._clock_pub
        now = time.perf_counter()
        if self._skip_ns is not None and stamp - clock.bag_time(now) > self._skip_ns:
            clock.start(stamp, now)  # over the gap: due now (rosbag publishes it even while paused)
            return
        if pause_topic and self._pause_for_topics:
            clock.pause(now)
        while True:
            now = time.perf_counter()
            if now >= self._next_ui:
                self._ui(now)
                if self._burst is not None:
                    clock.start(stamp, now)  # stay paused, at this message's time
                    return
                if self._seek_to is not None or self._stopping:
                    return
            due = clock.due(stamp)
            if now >= due:
                return
            deadline = min(due, self._next_ui)
            if clock_pub is not None and self.options.clock:
                if now >= self._next_tick:
                    self._tick_clock(now)
                deadline = min(deadline, self._next_tick)
            sleep_until(deadline)

    def _tick_clock(self, now: float) -> None:
        publisher = self._clock_pub
        if publisher is None or not self.options.clock or not self._started or now < self._next_tick:
            return
        publisher.publish_raw(self._clock_message(self.clock.bag_time(now)))
        period = 1.0 / self.options.hz
        self._next_tick += period
        if self._next_tick <= now:  # fell behind (paused terminal, slow subscriber): no burst
            self._next_tick = now + period

    def _ui(self, now: float) -> None:
        self._next_ui = now + UI_INTERVAL
        console = self.console
        for key in split_keys(console.read_keys()):
            if key == " ":
                if self.clock.paused:
                    self.clock.resume(now)
                else:
                    self.clock.pause(now)
            elif key in ("s", "RIGHT") and self.clock.paused and self._burst is None:
                self._burst = Burst(1)
            elif key == "t":
                self._pause_for_topics = not self._pause_for_topics
            elif key in ("UP", "DOWN"):  # rosbag2's 10 % a press
                self.clock.set_rate(self.clock.rate * (1.1 if key == "UP" else 0.9), now)
                if console.form == "ros2 bag":
                    console.say(f"[INFO] [rosbag2_player]: Set rate to {self.clock.rate:g}")
        self._commands(now)
        if console.show_status:
            bag_ns = self.clock.bag_time(now) if self._started else self.window[0]
            state = "PAUSED " if self.clock.paused else "RUNNING"
            elapsed = (bag_ns - self.reader.start_ns) / 1e9
            console.status(state, bag_ns / 1e9, elapsed, self.total, self.clock.rate)
