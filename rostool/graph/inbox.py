"""A subscription whose messages wait for the main thread (echo, delay).

Network threads append to a deque and wake the consumer only when it sleeps; the consumer drains
everything available and runs `on_idle` (e.g. flush stdout) before it waits. What waits is bounded by a
count and by bytes: past BYTE_BUDGET the oldest messages are dropped (and counted, one warning line a
second), as rostopic's subscriber queue drops, so a consumer that falls behind (output into a pipe nobody
reads) keeps its memory bounded whatever the messages' size.
"""

from __future__ import annotations

import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import Graph, Received, Subscription

BACKLOG_LIMIT = 20000
BYTE_BUDGET = 64 * 1024 * 1024  # payload bytes waiting for the consumer


class Inbox:
    """Collects messages from network threads; the caller iterates in its own thread."""

    def __init__(self, graph: Graph, topic: str) -> None:
        self._items: deque[Received | str] = deque()
        self._wake = threading.Event()
        self._bytes = 0  # payload bytes in _items
        self._count_lock = threading.Lock()
        self.dropped = 0
        self._warned = (0, 0.0)  # dropped count and time of the last warning
        self.subscription: Subscription = graph.subscribe(topic, self._put, self._error)

    def _put(self, received: Received | str) -> None:
        while len(self._items) > BACKLOG_LIMIT:  # backpressure onto TCP instead of unbounded memory
            time.sleep(0.001)
        size = _size(received)
        with self._count_lock:
            self._bytes += size
            self._items.append(received)
            while self._bytes > BYTE_BUDGET and len(self._items) > 1:
                oldest = self._items.popleft()
                self._bytes -= _size(oldest)
                self.dropped += 1
        if self.dropped:  # said here: the consumer may be stuck writing to a pipe nobody reads
            self._warn_dropped()
        if not self._wake.is_set():
            self._wake.set()

    def _take(self) -> Received | str:
        with self._count_lock:
            item = self._items.popleft()
            self._bytes -= _size(item)
        return item

    def _warn_dropped(self) -> None:
        count, when = self._warned
        now = time.monotonic()
        if self.dropped > count and now - when >= 1.0:
            sys.stderr.write(
                f"rostool: warning: dropped {self.dropped - count} messages: the output is not read as fast "
                f"as they come ({BYTE_BUDGET // (1024 * 1024)} MB wait at most)\n"
            )
            self._warned = (self.dropped, now)

    def _error(self, message: str) -> None:
        self._put(message)

    def messages(
        self, timeout: float | None = None, on_idle: Callable[[], None] | None = None
    ) -> Iterator[Received]:
        """Yield messages as they come; RostoolError(exit 1) after `timeout` s without one."""
        items, wake = self._items, self._wake
        last = time.monotonic()
        while True:
            try:
                item = self._take()
            except IndexError:
                if on_idle is not None:
                    on_idle()
                wake.clear()
                if items:
                    continue
                if timeout is not None and time.monotonic() - last >= timeout:
                    raise RostoolError(f"no message within {timeout:g} s", exit_code=1) from None
                wake.wait(0.2)
                continue
            if isinstance(item, str):
                raise RostoolError(item)
            last = time.monotonic() if timeout is not None else last
            yield item

    def close(self) -> None:
        self.subscription.close()


def _size(item: Received | str) -> int:
    payload = getattr(item, "payload", None)
    return len(payload) if payload is not None else 0


def decoded(received: Received, topic: str) -> Any:
    """The message, or one RostoolError line when a peer sent bytes that do not match its own type."""
    try:
        return received.decode()
    except RostoolError:
        raise
    except Exception as err:
        raise RostoolError(f"cannot decode a {received.type_name} message on {topic}: {err}") from err
