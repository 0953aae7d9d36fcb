"""What `bag plot` and `topic plot` share about their output: the -o FILE option, the --help text on
where the plot goes, and the figure written with its one-line summary on stderr."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import click

from rostool.output.plot_data import Series

OUTPUT_HELP = """\b
Output: -o FILE draws a .png, .svg or .pdf (matplotlib); else on a terminal a braille plot (plotille);
else (a pipe, or --csv) CSV rows `time,series,value`: time in exact seconds (bag time, or the header
stamp with --header-stamp), one row per number, in message order. Files and terminal plots need
`pip install 'rostool[plot]'`; CSV needs nothing."""


def output_file_option(help_text: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """`-o/--output FILE` (a Path; the suffix says the format)."""
    return click.option(
        "-o",
        "--output",
        type=click.Path(dir_okay=False, path_type=Path),
        metavar="FILE",
        help=help_text,
    )


def save_figure(
    series: Sequence[Series], output: Path, origin_ns: int, header_stamp: bool, title: str = ""
) -> None:
    """Draw the series to `output` and say so on stderr, with the points of each series."""
    from rostool.output.plot_draw import save

    save(series, output, origin_ns, header_stamp, title)
    click.echo(f"wrote {output} ({', '.join(f'{s.name}: {len(s.values)}' for s in series)} points)", err=True)
