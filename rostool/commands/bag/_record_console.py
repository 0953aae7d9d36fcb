"""The terminal side of `bag record`: the live dashboard (a progress line when not on a terminal), and pausing
(space on a terminal, SIGUSR1)."""

from __future__ import annotations

import collections
import contextlib
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator

from rostool.bag.play_console import Console
from rostool.bag.record_options import RecordStatus

KEY_POLL = 0.05  # seconds between looks at the keyboard


class RecordDashboard:
    """On a terminal: a header line and one line per topic (messages, rate, bandwidth, bytes written,
    dropped, and throttled by --max-rate), redrawn in place (rosbag_fancy's idea)."""

    WINDOW = 2.0  # seconds the rate and bandwidth are averaged over

    def __init__(self) -> None:
        self._drawn = 0  # lines of the last drawing still on the screen
        self._history: collections.deque[tuple[float, dict[str, tuple[int, int]]]] = collections.deque()
        self._started = time.monotonic()
        self._path = ""
        self._bytes = 0

    def __call__(self, status: RecordStatus) -> None:
        now = time.monotonic()
        self._history.append((now, {t: (s.messages, s.bytes) for t, s in status.per_topic.items()}))
        while len(self._history) > 2 and now - self._history[1][0] >= self.WINDOW:
            self._history.popleft()
        if str(status.path) != ".":  # the final status comes after the file was closed
            self._path, self._bytes = str(status.path), status.bytes
        self._draw(self.lines(status, now))

    def lines(self, status: RecordStatus, now: float) -> list[str]:
        from rostool.graph.rates import format_bytes

        elapsed = int(now - self._started)
        state = " [PAUSED]" if status.paused else ""
        if status.buffered is not None:
            state += f" [SNAPSHOT MODE: {status.buffered} msgs buffered]"
        rows = [("topic", "msgs", "rate", "bandwidth", "written", "dropped", "throttled")]
        then, before = self._history[0]
        span = now - then
        for topic, s in status.per_topic.items():
            old_msgs, old_bytes = before.get(topic, (0, 0))
            rate = (s.messages - old_msgs) / span if span > 0 else 0.0
            bandwidth = (s.bytes - old_bytes) / span if span > 0 else 0.0
            rows.append((topic, str(s.messages), f"{rate:.1f}/s", f"{format_bytes(bandwidth)}/s",
                         format_bytes(s.bytes), str(s.dropped), str(s.throttled)))  # fmt: skip
        if not any(s.throttled for s in status.per_topic.values()):
            rows = [row[:-1] for row in rows]
        widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
        table = ["  " + "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in
                 enumerate(zip(row, widths, strict=True))) for row in rows]  # fmt: skip
        header = (  # the state first: a long path is what the terminal's width cuts off
            f" recording{state} {elapsed // 60:02d}:{elapsed % 60:02d}, {status.messages} msgs on "
            f"{status.topics} topic{'' if status.topics == 1 else 's'}, {format_bytes(self._bytes)}: "
            f"{self._path}"
        )
        return [header, *table]

    def _draw(self, lines: list[str]) -> None:
        width = max(20, shutil.get_terminal_size().columns - 1)  # no line may wrap: redrawing counts lines
        out = [f"\x1b[{self._drawn}F"] if self._drawn else []
        out += [f"\x1b[2K{line[:width]}\n" for line in lines]
        out.append("\x1b[J")  # a shorter drawing leaves nothing of the last one below it
        sys.stderr.write("".join(out))
        sys.stderr.flush()
        self._drawn = len(lines)

    def end(self) -> None:
        """Leave the last drawing where it is; what is written next goes below it."""
        self._drawn = 0


class PlainProgress:
    """Not on a terminal: one progress line every `interval` seconds."""

    def __init__(self, interval: float) -> None:
        self.interval = interval
        self._next = time.monotonic() + interval

    def __call__(self, status: RecordStatus) -> None:
        from rostool.graph.rates import format_bytes

        now = time.monotonic()
        if now < self._next or str(status.path) == ".":
            return
        self._next = now + self.interval
        paused = " (paused)" if status.paused else ""
        if status.buffered is not None:
            paused += f" ({status.buffered} msgs buffered for a snapshot)"
        dropped = f", {status.dropped} dropped" if status.dropped else ""
        sys.stderr.write(
            f"rostool: recording {status.path}{paused}: {status.messages} msgs on {status.topics} topic"
            f"{'' if status.topics == 1 else 's'}, {format_bytes(status.bytes)}{dropped}\n"
        )
        sys.stderr.flush()

    def end(self) -> None:
        pass


@contextlib.contextmanager
def pause_controls(
    toggle: Callable[[], None], keyboard: bool, snapshot: Callable[[], None] | None = None
) -> Iterator[bool]:
    """While recording: space (when stdin is this process's terminal) and SIGUSR1 call `toggle`; in snapshot
    mode 's' and SIGUSR2 call `snapshot`. Yields whether the keyboard is read."""
    console = Console(status=False, keyboard=keyboard and Console.detect(quiet=True).keyboard)
    done = threading.Event()
    previous = {}
    if threading.current_thread() is threading.main_thread():
        previous[signal.SIGUSR1] = signal.signal(signal.SIGUSR1, lambda _signum, _frame: toggle())
        if snapshot is not None:
            previous[signal.SIGUSR2] = signal.signal(signal.SIGUSR2, lambda _signum, _frame: snapshot())
    with console:
        reader = None
        if console.keyboard:

            def read_keys() -> None:
                while not done.wait(KEY_POLL):
                    for key in console.read_keys():
                        if key == " ":
                            toggle()
                        elif key == "s" and snapshot is not None:
                            snapshot()

            reader = threading.Thread(target=read_keys, name="record-keys", daemon=True)
            reader.start()
        try:
            yield console.keyboard
        finally:
            done.set()
            if reader is not None:
                reader.join()
            for signum, handler in previous.items():
                signal.signal(signum, handler)
