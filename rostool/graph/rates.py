"""Running statistics for `topic hz`, `topic bw` and `topic delay`, computed as rostopic does.

Unbounded windows keep running sums (O(1) memory, so hours at 20 k msg/s cost nothing); `-w N`
keeps only the last N samples.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rostool.output.rate_text import format_bytes

if TYPE_CHECKING:
    from rostool.graph.base import Received

__all__ = [
    "RateMeter", "RunningStats", "SizeMeter", "Summary", "arrival_clock", "format_bytes", "fresh_rates",
]  # fmt: skip


def arrival_clock() -> Callable[[Received], float]:
    """When a message reached its reader (the graph daemon's, when relayed), on this process's monotonic
    clock: not when the verb's callback ran, or a relayed frame's trip over the socket would show as
    jitter."""
    offset = time.time() - time.monotonic()
    return lambda received: received.recv_time_ns / 1e9 - offset


@dataclass
class Summary:
    count: int  # samples in the window
    mean: float
    minimum: float
    maximum: float
    std_dev: float


class RunningStats:
    """Mean, min, max and population std dev over all samples, or over the last `window` samples."""

    def __init__(self, window: int | None = None) -> None:
        self._window: deque[float] | None = deque(maxlen=window) if window else None
        self._n = 0
        self._mean = 0.0
        self._m2 = 0.0  # Welford: sums of squares taken about the running mean stay exact for large values
        self._min = math.inf
        self._max = -math.inf

    def add(self, value: float) -> None:
        if self._window is not None:
            self._window.append(value)
            return
        self._n += 1
        delta = value - self._mean
        self._mean += delta / self._n
        self._m2 += delta * (value - self._mean)
        self._min = min(self._min, value)
        self._max = max(self._max, value)

    def summary(self) -> Summary | None:
        if self._window is not None:
            values = list(self._window)
            if not values:
                return None
            mean = sum(values) / len(values)
            var = sum((v - mean) ** 2 for v in values) / len(values)
            return Summary(len(values), mean, min(values), max(values), math.sqrt(var))
        if self._n == 0:
            return None
        var = max(self._m2 / self._n, 0.0)
        return Summary(self._n, self._mean, self._min, self._max, math.sqrt(var))


class RateMeter:
    """Counts every arrival of one topic; the rate is derived from inter-arrival gaps (rostopic hz)."""

    def __init__(self, window: int | None = None) -> None:
        self.gaps = RunningStats(window)
        self.total = 0
        self._last: float | None = None
        self._lock = threading.Lock()

    def arrived(self, now: float) -> None:
        with self._lock:
            self.total += 1
            if self._last is not None:
                self.gaps.add(now - self._last)
            self._last = now

    def summary(self) -> Summary | None:
        with self._lock:
            return self.gaps.summary()


class SizeMeter:
    """Message sizes and arrival times over the last `window` messages (rostopic bw)."""

    def __init__(self, window: int = 100) -> None:
        self._samples: deque[tuple[float, int]] = deque(maxlen=window)
        self._lock = threading.Lock()

    def arrived(self, now: float, size: int) -> None:
        with self._lock:
            self._samples.append((now, size))

    def bandwidth(self, now: float) -> tuple[float, Summary] | None:
        """Bytes per second over the window, and the size statistics."""
        with self._lock:
            samples = list(self._samples)
        if len(samples) < 2:
            return None
        sizes = [size for _t, size in samples]
        elapsed = now - samples[0][0]
        total = sum(sizes)
        mean = total / len(sizes)
        summary = Summary(len(sizes), mean, min(sizes), max(sizes), 0.0)
        return (total / elapsed if elapsed > 0 else 0.0), summary


def fresh_rates(
    meters: Mapping[str, RateMeter], printed: dict[str, int]
) -> list[tuple[str, float, Summary, int]]:
    """(topic, rate, gap statistics, messages counted) of each topic that got messages since its last report;
    `printed` (topic -> messages counted at its last report) is updated."""
    rows = []
    for topic_name, meter in meters.items():
        summary = meter.summary()
        if summary is None or printed.get(topic_name) == meter.total:
            continue
        printed[topic_name] = meter.total
        rate = 1.0 / summary.mean if summary.mean > 0 else 0.0
        rows.append((topic_name, rate, summary, meter.total))
    return rows
