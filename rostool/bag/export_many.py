"""`bag export` of one bag or many: each bag exported on its own (in local processes or Ray tasks) and the
results summed. Into object storage each bag is written to a local folder first, uploaded when complete."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

from rostool.bag.export import ExportOptions, ExportResult
from rostool.bag.many import BagItem, Results


def export_bags(
    items: Sequence[BagItem],
    options: ExportOptions,
    remote_out: Any,
    jobs: int | None,
    keep_going: bool,
    runner: Callable[..., Results[ExportResult]] | None,
) -> tuple[ExportResult, int]:
    """The sum of what was exported, and of how many bags (fewer than given with `keep_going`)."""
    from rostool.bag.many import successes

    several = len(items) > 1
    total = ExportResult("")
    exported = 0
    work = partial(_export_one, options, several, remote_out)
    for _item, result in successes(work, items, jobs, "exporting", keep_going, runner=runner):
        exported += 1
        total.messages += result.messages
        total.images += result.images
        total.files.extend(result.files)
    return total, exported


def _export_one(options: ExportOptions, several: bool, remote_out: Any, item: BagItem) -> ExportResult:
    """One bag's export; into object storage (`remote_out`): written locally, uploaded when complete."""
    import sys

    from rostool.bag.export import export_bag

    progress = not several and sys.stderr.isatty()
    partition = item.name if several else None
    if remote_out is None:
        return export_bag(item.path, options, partition=partition, progress=progress)
    import tempfile
    from dataclasses import replace

    from rostool.bag.remote import upload

    with tempfile.TemporaryDirectory(prefix="rostool-export-") as stage:
        result = export_bag(
            item.path, replace(options, out=Path(stage)), partition=partition, progress=progress
        )
        result.files = upload(Path(stage), remote_out)
    return result
