"""A subscription whose messages wait for the main thread (echo, delay).

Network threads append to a deque (no lock per message) and wake the consumer only when it sleeps;
the consumer drains everything available and runs `on_idle` (e.g. flush stdout) before it waits.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Iterator

from rostool.errors import RostoolError
from rostool.graph.base import Graph, Received, Subscription

BACKLOG_LIMIT = 20000


class Inbox:
    """Collects messages from network threads; the caller iterates in its own thread."""

    def __init__(self, graph: Graph, topic: str) -> None:
        self._items: deque[Received | str] = deque()
        self._wake = threading.Event()
        self.subscription: Subscription = graph.subscribe(topic, self._put, self._error)

    def _put(self, received: Received | str) -> None:
        while len(self._items) > BACKLOG_LIMIT:  # backpressure onto TCP instead of unbounded memory
            time.sleep(0.001)
        self._items.append(received)
        if not self._wake.is_set():
            self._wake.set()

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
                item = items.popleft()
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
