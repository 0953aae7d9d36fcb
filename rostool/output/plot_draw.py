"""Plots of `Series`: matplotlib for files (-o .png/.svg/.pdf), plotille's braille canvas for terminals.

Why these: matplotlib is the standard, with wheels everywhere and exact vector output; plotille is pure
Python, draws with braille dots (4x the resolution of ASCII, like rqt_plot's curves in a terminal) and
its API has been stable for years. Both come with `pip install 'rostool[plot]'`.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Sequence
from datetime import datetime, timezone
from pathlib import Path

from rostool.errors import RostoolError
from rostool.output.plot_data import Series
from rostool.output.plot_deps import need

FILE_FORMATS = (".png", ".svg", ".pdf")
COLORS = ("bright_blue", "bright_red", "bright_green", "bright_yellow", "bright_magenta", "bright_cyan")


def x_label(origin_ns: int, header_stamp: bool) -> str:
    ms = origin_ns // 1_000_000
    when = datetime.fromtimestamp(ms // 1000, tz=timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    clock = "header stamp" if header_stamp else "time"
    return f"{clock}: seconds since {ms // 1000}.{ms % 1000:03d} ({when}.{ms % 1000:03d} UTC)"


def check_output(path: Path) -> None:
    if path.suffix.lower() not in FILE_FORMATS:
        raise RostoolError(f"{path}: unknown plot format; name the file .png, .svg or .pdf")


def save(series: Sequence[Series], path: Path, origin_ns: int, header_stamp: bool, title: str = "") -> None:
    """One figure, one line per series (its SVG group id is `series:NAME`), x in seconds since origin."""
    check_output(path)
    mpl = need("matplotlib", "plot")
    mpl.use("Agg")
    import matplotlib.pyplot as plt

    # every point is drawn (no path simplification): the file holds the data, not a resampling
    with mpl.rc_context({"svg.fonttype": "none", "path.simplify": False, "font.size": 9}):
        fig, ax = plt.subplots(figsize=(9, 4.8), layout="constrained")
        try:
            for one in series:
                xs = [(t - origin_ns) / 1e9 for t in one.times_ns]
                ax.plot(xs, one.values, label=one.name, gid=f"series:{one.name}", linewidth=1.2)
            ax.set_xlabel(x_label(origin_ns, header_stamp))
            ax.grid(True, alpha=0.3)
            if title:
                ax.set_title(title)
            if series:
                ax.legend(loc="best")
            fig.savefig(path, dpi=150)
        finally:
            plt.close(fig)


def terminal_text(
    series: Sequence[Series], origin_ns: int, header_stamp: bool, size: tuple[int, int] | None = None,
    x_span: tuple[float, float] | None = None,
) -> str:  # fmt: skip
    """The plot as braille text with ANSI colors, sized to the terminal (or `size` columns x rows)."""
    plotille = need("plotille", "plot")
    columns, rows = size or shutil.get_terminal_size((100, 30))
    fig = plotille.Figure()
    fig.width = max(columns - 16, 20)  # room for the y-axis labels
    fig.height = max(rows - 7 - len(series), 5)  # x axis, legend, status line
    fig.color_mode = "names"
    fig.origin = False
    fig.x_label = "s"
    fig.y_label = "value"
    low = high = None
    right = 0.0
    for index, one in enumerate(series):
        points = [((t - origin_ns) / 1e9, v) for t, v in zip(one.times_ns, one.values, strict=True)]
        points = [(x, v) for x, v in points if math.isfinite(v)]
        if not points:
            continue
        xs, ys = zip(*points, strict=True)
        right = max(right, *xs)
        low = min(ys) if low is None else min(low, *ys)
        high = max(ys) if high is None else max(high, *ys)
        fig.plot(xs, ys, label=one.name, lc=COLORS[index % len(COLORS)])
    if low is not None and high is not None and low == high:  # a constant: give it some room
        fig.set_y_limits(min_=low - 1, max_=high + 1)
    left, right = x_span or (0.0, right)
    fig.set_x_limits(min_=left, max_=max(right, left + 1e-3))
    return f"{fig.show(legend=True)}\n{x_label(origin_ns, header_stamp)}"
