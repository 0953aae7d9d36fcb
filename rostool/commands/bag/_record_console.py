"""The terminal side of `bag record`: the progress line, and pausing (space on a terminal, SIGUSR1)."""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Callable, Iterator

from rostool.bag.play_console import Console
from rostool.bag.record_options import RecordStatus

KEY_POLL = 0.05  # seconds between looks at the keyboard


class RecordProgress:
    """One status line on stderr, rewritten in place."""

    def __init__(self) -> None:
        self._shown = False

    def __call__(self, status: RecordStatus) -> None:
        from rostool.graph.rates import format_bytes

        dropped = f", {status.dropped} dropped" if status.dropped else ""
        state = " [PAUSED]" if status.paused else ""
        sys.stderr.write(
            f"\r recording{state} {status.path}: {status.messages} msgs on {status.topics} "
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


@contextlib.contextmanager
def pause_controls(toggle: Callable[[], None], keyboard: bool) -> Iterator[bool]:
    """While recording: space (when stdin is this process's terminal) and SIGUSR1 call `toggle`. Yields
    whether the keyboard is read."""
    console = Console(status=False, keyboard=keyboard and Console.detect(quiet=True).keyboard)
    done = threading.Event()
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGUSR1, lambda _signum, _frame: toggle())
    with console:
        reader = None
        if console.keyboard:

            def read_keys() -> None:
                while not done.wait(KEY_POLL):
                    if " " in console.read_keys():
                        toggle()

            reader = threading.Thread(target=read_keys, name="record-keys", daemon=True)
            reader.start()
        try:
            yield console.keyboard
        finally:
            done.set()
            if reader is not None:
                reader.join()
            if previous is not None:
                signal.signal(signal.SIGUSR1, previous)
