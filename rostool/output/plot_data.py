"""Numbers taken out of messages for `bag plot` and `topic plot`: field paths and their series.

A path names a topic and a field, as rqt_plot takes them: `/odom/pose/pose/position/x` (the longest
known topic that prefixes it is the topic) or `/odom.pose.pose.position.x` (the topic ends at the first
dot: use this form for a topic nobody publishes yet). Indexes: `/scan/ranges[0]` or `/scan/ranges/0`.
A field that is a message or an array plots every number inside it (`/turtle1/pose` -> x, y, theta...).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable
from dataclasses import dataclass, field
from typing import Any

from rostool.errors import RostoolError
from rostool.output.plain import select_field, to_plain


@dataclass(frozen=True)
class FieldSpec:
    text: str  # as given: the series' name
    topic: str
    field: str  # "" for the whole message
    sep: str  # "/" or ".": how names of the numbers inside a message field continue `text`


@dataclass
class Series:
    name: str
    times_ns: list[int] = field(default_factory=list)
    values: list[float] = field(default_factory=list)

    def trim_before(self, start_ns: int) -> None:
        keep = next((i for i, t in enumerate(self.times_ns) if t >= start_ns), len(self.times_ns))
        if keep:
            del self.times_ns[:keep], self.values[:keep]


def parse_spec(text: str, topics: Collection[str]) -> FieldSpec:
    """Split TOPIC/FIELD at the longest known topic; else TOPIC.FIELD at the first dot."""
    given = text if text.startswith("/") else "/" + text
    matches = [t for t in topics if given == t or (given.startswith(t) and given[len(t)] in "/.[")]
    if matches:
        topic = max(matches, key=len)
        rest = given[len(topic) :]
        return FieldSpec(given, topic, rest.lstrip("/."), "." if rest.startswith(".") else "/")
    if "." in given:
        topic, _, rest = given.partition(".")
        return FieldSpec(given, topic, rest, ".")
    have = ", ".join(sorted(topics)[:8]) + (", ..." if len(topics) > 8 else "") if topics else "none"
    raise RostoolError(
        f"{given}: no such topic (known: {have}); "
        "write TOPIC/FIELD or TOPIC.FIELD, e.g. /odom/pose/pose/position/x"
    )


def numbers(value: Any, name: str, sep: str) -> list[tuple[str, float]]:
    """Every number in a field value, named by its path below `name` (bools count as 0/1)."""
    found: list[tuple[str, float]] = []

    def walk(item: Any, path: str) -> None:
        if isinstance(item, (bool, int, float)):  # bools count as 0/1
            found.append((path, float(item)))
        elif isinstance(item, dict):
            for key, inner in item.items():
                walk(inner, f"{path}{sep}{key}")
        elif isinstance(item, list):
            for index, inner in enumerate(item):
                walk(inner, f"{path}[{index}]" if sep == "." else f"{path}/{index}")

    walk(to_plain(value, "ros2"), name)
    return found


def header_stamp_ns(msg: object, topic: str) -> int:
    try:
        stamp = to_plain(select_field(msg, "header.stamp"), "ros2")
    except LookupError as err:
        raise RostoolError(
            f"{topic} has no header.stamp: leave out --header-stamp to plot against the bag or receive time"
        ) from err
    return int(stamp["sec"]) * 1_000_000_000 + int(stamp["nanosec"])


class Sampler:
    """Turns messages into points of named series, in the order the specs were given."""

    def __init__(self, specs: Iterable[FieldSpec], header_stamp: bool = False) -> None:
        self.specs = list(specs)
        self.header_stamp = header_stamp
        self.series: dict[str, Series] = {}
        self._checked: set[FieldSpec] = set()
        self._rank: dict[str, tuple[int, int]] = {}
        self._first_ns: int | None = None  # the x origin; kept when a live window drops old points

    @property
    def topics(self) -> list[str]:
        return sorted({spec.topic for spec in self.specs})

    def add(self, topic: str, msg: object, time_ns: int) -> list[tuple[str, int, float]]:
        """The new points (series name, time ns, value) this message gives."""
        points: list[tuple[str, int, float]] = []
        when = header_stamp_ns(msg, topic) if self.header_stamp else time_ns
        for spec in self.specs:
            if spec.topic != topic:
                continue
            try:
                value = select_field(msg, spec.field) if spec.field else msg
            except LookupError as err:
                raise RostoolError(
                    f"{spec.text}: {err.args[0]}; see the layout with `rostool msg show`"
                ) from err
            found = numbers(value, spec.text, spec.sep)
            if not found and spec not in self._checked:
                kind = type(to_plain(value, "ros2")).__name__
                raise RostoolError(f"{spec.text} is not a number (it is a {kind}); name a numeric field")
            self._checked.add(spec)
            for name, number in found:
                series = self.series.get(name)
                if series is None:
                    series = self.series[name] = Series(name)
                    self._rank[name] = (self.specs.index(spec), len(self._rank))
                if self._first_ns is None or when < self._first_ns:
                    self._first_ns = when
                series.times_ns.append(when)
                series.values.append(number)
                points.append((name, when, number))
        return points

    def ordered(self) -> list[Series]:
        """The series in the order their paths were given (numbers inside one field in message order)."""
        return sorted(self.series.values(), key=lambda s: self._rank[s.name])

    def start_ns(self) -> int | None:
        return self._first_ns


def seconds(time_ns: int) -> str:
    """Exact decimal seconds of a nanosecond time (CSV keeps what the bag holds)."""
    sign = "-" if time_ns < 0 else ""
    whole, frac = divmod(abs(time_ns), 1_000_000_000)
    return f"{sign}{whole}.{frac:09d}"


def csv_header() -> str:
    return "time,series,value"


def csv_row(name: str, time_ns: int, value: float) -> str:
    text = repr(value) if math.isfinite(value) else str(value)
    return f"{seconds(time_ns)},{name},{text}"  # ROS names hold no commas or quotes
