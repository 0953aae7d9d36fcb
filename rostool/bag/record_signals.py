"""The recorder's signals: SIGINT, SIGTERM and SIGHUP end a recording cleanly. A module of its own (the
standard library only), so `bag record` takes the signals before it imports the recorder and opens the
graph."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType


@contextlib.contextmanager
def stop_on_signals(stop: threading.Event) -> Iterator[None]:
    """SIGINT, SIGTERM and SIGHUP (terminal closed) set `stop`, so the recording ends cleanly; a second
    signal aborts at once (the .active file is then left for `bag reindex`)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, _frame: FrameType | None) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    previous = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
