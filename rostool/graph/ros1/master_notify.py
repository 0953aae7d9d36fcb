"""Callbacks from the master to nodes (publisherUpdate, paramUpdate, shutdown), off the request path.

Each target URI gets its own short-lived worker thread that drains that node's queue in order, so a
slow or dead node only delays its own callbacks. A queued callback superseded by a newer one for the
same topic or parameter key is dropped: the node only needs the latest state, and the order of the
remaining callbacks is kept.
"""

from __future__ import annotations

import contextlib
import threading
import xmlrpc.client
from collections import OrderedDict
from typing import Any

from rostool.graph.ros1.master_client import server_proxy

CALLER_ID = "/master"
CALL_TIMEOUT = 15.0  # seconds; a node that does not answer in time misses that callback

Task = tuple[str, str]  # (method, key): a newer task with the same pair supersedes a queued one


class Notifier:
    def __init__(self, timeout: float = CALL_TIMEOUT) -> None:
        self._timeout = timeout
        self._lock = threading.Lock()
        self._queues: dict[str, OrderedDict[Task, tuple[Any, ...]]] = {}
        self._closed = False

    def post(self, api: str, method: str, key: str, *args: Any) -> None:
        """Queue `api.method(CALLER_ID, *args)`; returns at once."""
        with self._lock:
            if self._closed:
                return
            queue = self._queues.get(api)
            start_worker = queue is None
            if queue is None:
                queue = self._queues[api] = OrderedDict()
            queue.pop((method, key), None)
            queue[(method, key)] = args
        if start_worker:
            threading.Thread(target=self._drain, args=(api,), name=f"notify {api}", daemon=True).start()

    def busy(self) -> bool:
        """True while any callback is queued or in flight."""
        with self._lock:
            return bool(self._queues)

    def close(self) -> None:
        with self._lock:
            self._closed = True
            self._queues.clear()

    def _drain(self, api: str) -> None:
        proxy: xmlrpc.client.ServerProxy | None = None
        with contextlib.suppress(OSError):  # not an http:// URI: its callbacks are dropped
            proxy = server_proxy(api, self._timeout)
        try:
            while True:
                with self._lock:
                    queue = self._queues.get(api)
                    if not queue:
                        self._queues.pop(api, None)
                        return
                    (method, _key), args = queue.popitem(last=False)
                if proxy is None:
                    continue
                try:
                    getattr(proxy, method)(CALLER_ID, *args)
                except Exception:
                    # Dead, hung or broken nodes are normal in a ROS graph; the callback is simply lost.
                    proxy("close")()
        finally:
            if proxy is not None:
                proxy("close")()
