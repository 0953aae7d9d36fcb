"""Playback time: which wall time each bag time is due at, with rate and pause, and precise waiting.

Every message's due time is computed from one origin (wall time, bag time), never from the previous
message, so lateness never accumulates: due = wall_origin + (stamp - bag_origin) / rate. Pausing moves the
wall origin by the time spent paused. Waiting sleeps until just before the deadline and spins the rest:
time.sleep overshoots by 50-100 us on Linux, spinning the last 0.3 ms keeps the error in microseconds.
"""

from __future__ import annotations

import time

SPIN = 0.0003  # seconds before a deadline where sleeping stops and spinning starts


class PlayClock:
    """Maps bag time (ns) to wall time (time.perf_counter seconds) and back."""

    def __init__(self, rate: float = 1.0) -> None:
        if rate <= 0:
            raise ValueError("rate must be positive")
        self.rate = rate
        self._wall0 = 0.0
        self._bag0 = 0
        self.paused_at: float | None = None

    def start(self, bag_ns: int, now: float) -> None:
        """`bag_ns` is due at wall time `now`."""
        self._wall0, self._bag0 = now, bag_ns
        if self.paused_at is not None:
            self.paused_at = now

    def due(self, stamp_ns: int) -> float:
        """Wall time at which bag time `stamp_ns` is due (in the future while paused)."""
        due = self._wall0 + (stamp_ns - self._bag0) / 1e9 / self.rate
        if self.paused_at is not None:
            return max(due, time.perf_counter() + 3600.0)
        return due

    def set_rate(self, rate: float, now: float) -> None:
        """Play at `rate` from now on: the bag time reached so far stays where it is."""
        if rate <= 0:
            raise ValueError("rate must be positive")
        at = self.paused_at if self.paused_at is not None else now
        self._bag0, self._wall0 = self.bag_time(now), at
        self.rate = rate

    def bag_time(self, now: float) -> int:
        at = self.paused_at if self.paused_at is not None else now
        return self._bag0 + int((at - self._wall0) * self.rate * 1e9)

    @property
    def paused(self) -> bool:
        return self.paused_at is not None

    def pause(self, now: float) -> None:
        if self.paused_at is None:
            self.paused_at = now

    def resume(self, now: float) -> None:
        if self.paused_at is not None:
            self._wall0 += now - self.paused_at
            self.paused_at = None


def sleep_until(deadline: float) -> None:
    """Return at `deadline` (time.perf_counter seconds), within a few microseconds."""
    clock = time.perf_counter
    remaining = deadline - clock()
    if remaining > SPIN:
        time.sleep(remaining - SPIN)
    while clock() < deadline:
        pass
