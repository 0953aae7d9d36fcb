"""`bag convert`/`bag filter` over several bags or a directory of bags: each bag copied on its own, in
parallel processes, into one output folder."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

from rostool.bag.many import BagItem
from rostool.bag.message_filter import message_filter
from rostool.errors import RostoolError

CopyReport = Callable[[BagItem, int, int, str], None]  # item, messages written, topics, where ("": none)


@dataclass(frozen=True)
class CopyJob:
    """What convert/filter do to each bag of several (plain data: it goes to worker processes)."""

    out: str
    fmt: Any
    selection: Any
    expr: str | None
    distro: str
    force: bool
    like_input: bool


def is_fleet(sources: Sequence[str]) -> bool:
    """A SRC that is a directory of bags (not itself a bag)."""
    from rostool.bag.many import is_one_bag

    return any(Path(src).is_dir() and not is_one_bag(Path(src)) for src in sources)


def make_output_folder(path: Path) -> None:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RostoolError(f"{path}: cannot create the output folder: {err.strerror or err}") from err


def copy_each(job: CopyJob, sources: Sequence[str], jobs: int | None, report: CopyReport) -> None:
    """Copy every bag of `sources` into the folder `job.out`; `report` hears of each bag copied, in order,
    once the progress bar is gone (also when a bag failed)."""
    from rostool.bag.many import expand, successes

    items = expand(sources)
    make_output_folder(Path(job.out))
    done: list[tuple[BagItem, int, int, str]] = []
    try:
        for item, (written, topics, dst) in successes(partial(_copy_one, job), items, jobs, "copying"):
            done.append((item, written, topics, dst))
    finally:  # after the progress bar is gone
        for item, written, topics, dst in done:
            report(item, written, topics, dst)


def _present_topics(item: BagItem, job: CopyJob) -> list[str]:
    from rostool.bag.reader import BagReader

    with BagReader([item.path], job.distro) as reader:
        return [name for name in job.selection.topics if name in reader.topics]


def _copy_one(job: CopyJob, item: BagItem) -> tuple[int, int, str]:
    from rostool.bag.convert import copy_bags

    selection = dataclasses.replace(job.selection, predicate=message_filter(job.expr))
    if job.selection.topics:  # a fleet: not every bag has every topic
        selection.topics = _present_topics(item, job)
        if not selection.topics:
            return 0, 0, ""
    suffix = {"bag": ".bag", "mcap": ".mcap", "db3": ".db3"}.get(job.fmt or "", "")
    if job.fmt is None and job.like_input and item.path.is_file():
        suffix = item.path.suffix
    dst = str(Path(job.out) / f"{item.name}{suffix}")
    result = copy_bags(
        [item.path], dst, job.fmt, selection, distro=job.distro, force=job.force, progress=False,
        like_input=job.like_input,
    )  # fmt: skip
    return result.written, len(result.topics), dst
