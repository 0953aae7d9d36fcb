"""What `bag convert` and `bag filter` share: output options, and the line printed for each bag written."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import click

from rostool.commands.bag._options import TIME_HELP

if TYPE_CHECKING:
    from rostool.bag.copy_many import CopyJob
    from rostool.bag.many import BagItem

format_option = click.option(
    "--format",
    "fmt",
    type=click.Choice(["bag", "mcap", "db3"]),
    help="Output format when DST's name does not say (.bag, .mcap, .db3; other names: rosbag2 dir).",
)


def time_window_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """--start/--end: the messages outside are dropped."""
    func = click.option("--end", metavar="S", help=f"Drop messages after: {TIME_HELP}.")(func)
    return click.option("--start", metavar="S", help=f"Drop messages before: {TIME_HELP}.")(func)


def writing_options(output: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """--distro, --force and -j: how convert and filter write OUTPUT (DST, OUT)."""
    from rostool.commands.bag._options import distro_option, jobs_option

    force = click.option(
        "--force", is_flag=True, help=f"Replace {output} if it is a bag (never an input, nor other files)."
    )
    return lambda func: distro_option(force(jobs_option(func)))


def report(written: int, topics: int, dst: str) -> None:
    click.echo(f"wrote {written} messages on {topics} topics to {dst}", err=True)


def copy_fleet(job: CopyJob, sources: Sequence[str], jobs: int | None) -> None:
    from rostool.bag.copy_many import copy_each

    copy_each(job, sources, jobs, _report_item)


def _report_item(item: BagItem, written: int, topics: int, dst: str) -> None:
    if dst:
        report(written, topics, dst)
    else:
        click.echo(f"{item.path}: none of the --topics, nothing written", err=True)
