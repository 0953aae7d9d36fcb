"""Options and argument rules several bag verbs share."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import click

from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
TIME_HELP = "seconds since the epoch, or +S for S seconds after the bag's first message"


def distro_option(func: Callable[..., Any]) -> Callable[..., Any]:
    return click.option(
        "--distro",
        type=click.Choice(sorted(DISTROS)),
        default=DEFAULT_DISTRO,
        show_default=True,
        help="ROS 2 type store for bags that carry no message definitions.",
    )(func)


jobs_option = click.option(
    "-j",
    "--jobs",
    type=click.IntRange(min=1),
    metavar="N",
    help="Work on N bags at once, in parallel processes (default: the number of cores, once the bags "
    "hold 64 MB or more).",
)

topics_option = click.option(
    "--topics", multiple=True, metavar="T", help="Only these topics (repeatable, or comma-separated)."
)


def topic_list(values: Sequence[str]) -> list[str]:
    """`--topics /a --topics /b`, `--topics "/a /b"` and `--topics /a,/b` all work."""
    return [name for value in values for name in value.replace(",", " ").split()]


max_rate_option = click.option(
    "--max-rate", multiple=True, metavar="TOPIC:HZ",
    help="Keep at most HZ messages a second of TOPIC (1/HZ since the last one kept; repeatable).",
)  # fmt: skip
progress_option = click.option(
    "--progress", type=click.FloatRange(min=0), default=10.0, show_default=True, metavar="S",
    help="rostool: when stderr is not a terminal, a progress line every S seconds (0: none).",
)  # fmt: skip
