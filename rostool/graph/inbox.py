"""A subscription whose messages wait in a queue for the main thread (echo, delay)."""

from __future__ import annotations

import queue
import time
from collections.abc import Iterator

from rostool.errors import RostoolError
from rostool.graph.base import Graph, Received, Subscription


class Inbox:
    """Collects messages from network threads; the caller iterates in its own thread."""

    def __init__(self, graph: Graph, topic: str, maxsize: int = 10000) -> None:
        self._queue: queue.Queue[Received | str] = queue.Queue(maxsize)
        self.subscription: Subscription = graph.subscribe(topic, self._put, self._error)

    def _put(self, received: Received) -> None:
        self._queue.put(received)

    def _error(self, message: str) -> None:
        self._queue.put(message)

    def backlog(self) -> int:
        return self._queue.qsize()

    def messages(self, timeout: float | None = None) -> Iterator[Received]:
        """Yield messages as they come; RostoolError(exit 1) after `timeout` s without one."""
        while True:
            deadline = None if timeout is None else time.monotonic() + timeout
            while True:
                wait = 0.2 if deadline is None else min(0.2, deadline - time.monotonic())
                if wait <= 0:
                    raise RostoolError(f"no message within {timeout:g} s", exit_code=1)
                try:
                    item = self._queue.get(timeout=wait)
                    break
                except queue.Empty:
                    continue
            if isinstance(item, str):
                raise RostoolError(item)
            yield item

    def close(self) -> None:
        self.subscription.close()
