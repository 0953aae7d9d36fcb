"""Silences in a recording: stretches where a topic that was arriving steadily went quiet (a Wi-Fi link
that dropped, a publisher that stalled), so `bag record` can say how long it heard nothing. The bag stays
whole either way; this only notices."""

from __future__ import annotations

from dataclasses import dataclass, field

MIN_SILENCE_NS = 2_000_000_000  # a gap shorter than this is never called a silence
USUAL_TIMES = 5  # ... nor one shorter than this many of the topic's usual intervals
SETTLED_AFTER = 5  # messages a topic must have brought before its gaps count


@dataclass(frozen=True)
class Silence:
    topic: str
    start_ns: int  # receive time of the last message before it
    end_ns: int  # receive time of the first message after it

    @property
    def seconds(self) -> float:
        return (self.end_ns - self.start_ns) / 1e9


@dataclass
class SilenceWatch:
    """Fed each written message's topic and receive time (in order per topic)."""

    found: list[Silence] = field(default_factory=list)
    _last: dict[str, int] = field(default_factory=dict)
    _usual: dict[str, float] = field(default_factory=dict)  # a moving average of the topic's intervals
    _seen: dict[str, int] = field(default_factory=dict)

    def heard(self, topic: str, stamp: int) -> None:
        last = self._last.get(topic)
        self._last[topic] = stamp
        seen = self._seen[topic] = self._seen.get(topic, 0) + 1
        if last is None or stamp <= last:
            return
        gap = stamp - last
        usual = self._usual.get(topic)
        if usual is not None and seen > SETTLED_AFTER and gap >= max(MIN_SILENCE_NS, USUAL_TIMES * usual):
            self.found.append(Silence(topic, last, stamp))
            return  # a silence does not teach what is usual
        self._usual[topic] = gap if usual is None else 0.9 * usual + 0.1 * gap
