"""What `topic hz`, `topic bw` and `topic delay` print: rostopic's lines under ROS 1, ros2 topic's under
ROS 2, or one JSON object per topic and report."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Literal, Protocol

from rostool.output.json_text import dumps


class Stats(Protocol):
    count: int
    mean: float
    minimum: float
    maximum: float
    std_dev: float


RateRow = tuple[str, float, Stats, int]  # topic, messages per second, gap statistics, messages counted


def hz_report(
    rows: Sequence[RateRow], several: bool, as_json: bool, style: Literal["ros1", "ros2"]
) -> list[str]:
    """One report's texts, each echoed on its own; `rows` holds the topics that got messages since the last
    one: with none, rostopic says "no new messages", ros2 topic hz prints nothing."""
    if as_json:
        return [
            dumps({"topic": topic, "rate": rate, "min": s.minimum, "max": s.maximum, "std_dev": s.std_dev,
                   "window": s.count + 1, "received": total})
            for topic, rate, s, total in rows
        ]  # fmt: skip
    if not rows:
        return ["no new messages"] if style == "ros1" else []
    if not several:
        _topic, rate, s, _total = rows[0]
        return [f"average rate: {rate:.3f}\n{_spread(s, s.count + 1)}"]
    header = ("topic", "rate", "min_delta", "max_delta", "std_dev", "window")
    if style == "ros2":  # ros2 topic hz: fixed decimals, the header centred over its column
        cells = [(t, f"{r:.3f}", f"{s.minimum:.3f}", f"{s.maximum:.3f}", f"{s.std_dev:.5f}", str(s.count + 1))
                 for t, r, s, _ in rows]  # fmt: skip
        widths = [max(len(row[i]) for row in [header, *cells]) for i in range(len(header))]
        lines = ["   ".join(c.center(w) for c, w in zip(header, widths, strict=True))]
        lines += ["   ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) + " " for row in cells]
        lines.insert(1, "=" * len(lines[0]))
        return ["\n".join(lines)]
    table = [header] + [
        (t, f"{r:.4}", f"{s.minimum:.4}", f"{s.maximum:.4}", f"{s.std_dev:.4}", str(s.count + 1))
        for t, r, s, _ in rows
    ]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    lines = ["   ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) for row in table]
    lines.insert(1, "=" * len(lines[0]))
    return ["\n".join(lines)]


def delay_text(s: Stats) -> str:
    return f"average delay: {s.mean:.3f}\n{_spread(s, s.count)}"


def _spread(s: Stats, window: int) -> str:
    return f"\tmin: {s.minimum:.3f}s max: {s.maximum:.3f}s std dev: {s.std_dev:.5f}s window: {window}"


def bandwidth_text(rate: float, s: Stats, style: Literal["ros1", "ros2"]) -> str:
    """rostopic bw's two lines (B, KB, MB with two decimals each), or ros2 topic bw's (one unit for all four
    numbers, chosen by the rate)."""
    if style == "ros1":
        return (
            f"average: {format_bytes(rate)}/s\n\tmean: {format_bytes(s.mean)} min: "
            f"{format_bytes(s.minimum)} max: {format_bytes(s.maximum)} window: {s.count}"
        )
    show = _ros2_unit(rate)
    return (
        f"{show(rate)}/s from {s.count} messages\n"
        f"\tMessage size mean: {show(s.mean)} min: {show(s.minimum)} max: {show(s.maximum)}"
    )


BandwidthRow = tuple[str, float, Stats]  # topic, bytes per second, message size statistics


def bandwidth_report(
    rows: Sequence[BandwidthRow], several: bool, as_json: bool, style: Literal["ros1", "ros2"]
) -> list[str]:
    """One report's texts: one topic's lines (`bandwidth_text`), or a line per topic under a header."""
    if as_json:
        return [
            dumps({"topic": topic, "bandwidth": rate, "mean": s.mean, "min": s.minimum, "max": s.maximum,
                   "window": s.count})
            for topic, rate, s in rows
        ]  # fmt: skip
    if not rows:
        return []
    if not several:
        _topic, rate, s = rows[0]
        return [bandwidth_text(rate, s, style)]
    header = ("topic", "bandwidth", "mean", "min", "max", "window")
    cells = [header]
    for topic, rate, s in rows:
        show = format_bytes if style == "ros1" else _ros2_unit(rate)
        cells.append((topic, f"{show(rate)}/s", show(s.mean), show(s.minimum), show(s.maximum), str(s.count)))
    widths = [max(len(row[i]) for row in cells) for i in range(len(header))]
    lines = ["   ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() for row in cells]
    lines.insert(1, "=" * max(len(line) for line in lines))
    return ["\n".join(lines)]


def _ros2_unit(rate: float) -> Callable[[float], str]:
    """ros2 topic bw's one unit for a topic's four numbers, chosen by its rate."""
    scale, unit, digits = (1, "B", 0) if rate < 1000 else (1e3, "KB", 2) if rate < 1e6 else (1e6, "MB", 2)
    return lambda value: f"{value / scale:.{digits}f} {unit}"


def format_bytes(value: float) -> str:
    """rostopic bw style: B, KB, MB with two decimals."""
    if value < 1000:
        return f"{value:.2f}B"
    if value < 1_000_000:
        return f"{value / 1000:.2f}KB"
    return f"{value / 1_000_000:.2f}MB"
