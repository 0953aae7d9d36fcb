"""`bag export` of one bag or many: each bag exported on its own (in local processes or Ray tasks) and the
results summed. A big indexed .mcap can be cut into runs of chunks exported in parallel, whose tables are
then joined byte-wise (parquet_concat.py) into the files one export writes (`piece_bytes`; off by default
until the join is cheaper, see PIECE_BYTES). Into object storage each bag is
written to a local folder first, uploaded when complete."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

from rostool.bag.export import ExportOptions, ExportResult
from rostool.bag.many import BagItem, Results

# The least a piece of a bag holds (its worker's start-up must pay off); 0: bags are not cut. Off for now:
# measured on 2 cores, one 1 GB .mcap exported in 2.95 s whole and 3.57 s in two pieces, the join's
# pure-Python footer work (~0.9 s for two 142 MiB files of 339 row groups) eating the gain.
PIECE_BYTES = 0


def export_bags(
    items: Sequence[BagItem],
    options: ExportOptions,
    remote_out: Any,
    jobs: int | None,
    keep_going: bool,
    runner: Callable[..., Results[ExportResult]] | None,
    piece_bytes: int = PIECE_BYTES,
) -> tuple[ExportResult, int]:
    """The sum of what was exported, and of how many bags (fewer than given with `keep_going`)."""
    from rostool.bag.export import join_pieces
    from rostool.bag.many import successes

    several = len(items) > 1
    total = ExportResult("")
    exported = 0
    work = partial(_export_one, options, several, remote_out)
    cut = _cut(items, options, remote_out, jobs, runner is not None, piece_bytes)
    done: dict[str, list[ExportResult]] = {}  # a cut bag's pieces exported so far
    unfinished = {item.name for item in cut if item.pieces > 1}
    try:
        for item, result in successes(work, cut, jobs, "exporting", keep_going, runner=runner):
            if item.pieces > 1:
                done.setdefault(item.name, []).append(result)
                if len(done[item.name]) < item.pieces:
                    continue
                pieces = done.pop(item.name)
                joined = join_pieces([name for piece in pieces for name in piece.pieces])
                unfinished.discard(item.name)
                result = ExportResult(
                    result.bag,
                    messages=sum(piece.messages for piece in pieces),
                    files=[name for piece in pieces for name in piece.files] + joined,
                )
            exported += 1
            total.messages += result.messages
            total.images += result.images
            total.files.extend(result.files)
    finally:  # a bag whose pieces did not all succeed (or were not all waited for) leaves nothing behind
        if options.out is not None:
            for name in unfinished:
                _remove_pieces(options.out, name if several else None)
    return total, exported


def _cut(
    items: Sequence[BagItem],
    options: ExportOptions,
    remote_out: Any,
    jobs: int | None,
    ray: bool,
    piece_bytes: int,
) -> list[BagItem]:
    """The work: each bag, and each big .mcap (Parquet tables only, no images, a local output) cut into as
    many pieces as there are workers, each of at least `piece_bytes` (0: none is cut)."""
    from rostool.bag.many import PARALLEL_FROM_BYTES, default_jobs

    if piece_bytes <= 0:
        return list(items)
    sizes = [_mcap_bytes(item.path) for item in items]
    workers = jobs or (default_jobs() if ray or sum(sizes) >= PARALLEL_FROM_BYTES else 1)
    if workers < 2 or options.fmt != "parquet" or options.images is not None or remote_out is not None:
        return list(items)
    work = []
    for item, size in zip(items, sizes, strict=True):
        pieces = max(1, min(workers, size // max(1, piece_bytes)))
        work.extend(replace(item, piece=k, pieces=pieces) for k in range(pieces))
    return work


def _remove_pieces(out: Path, partition: str | None) -> None:
    from rostool.bag.export import PIECE_SUFFIX

    pattern = f"*/bag={partition}/*{PIECE_SUFFIX}*" if partition is not None else f"*{PIECE_SUFFIX}*"
    for leftover in out.glob(pattern):
        leftover.unlink(missing_ok=True)


def _mcap_bytes(path: Path | Any) -> int:
    """The bytes of a local .mcap bag (a file, or a rosbag2 directory of them); 0 for anything else."""
    if not isinstance(path, Path):
        return 0
    try:
        if path.is_dir():
            return sum(entry.stat().st_size for entry in path.glob("*.mcap") if entry.is_file())
        return path.stat().st_size if path.suffix == ".mcap" else 0
    except OSError:
        return 0


def _export_one(options: ExportOptions, several: bool, remote_out: Any, item: BagItem) -> ExportResult:
    """One bag's export (or one piece of it); into object storage (`remote_out`): written locally, uploaded
    when complete."""
    import sys

    from rostool.bag.export import export_bag

    progress = not several and item.pieces == 1 and sys.stderr.isatty()
    partition = item.name if several else None
    piece = (item.piece, item.pieces) if item.pieces > 1 else None
    if remote_out is None:
        return export_bag(item.path, options, partition=partition, progress=progress, piece=piece)
    import tempfile

    from rostool.bag.remote import upload

    with tempfile.TemporaryDirectory(prefix="rostool-export-") as stage:
        result = export_bag(
            item.path, replace(options, out=Path(stage)), partition=partition, progress=progress
        )
        result.files = upload(Path(stage), remote_out)
    return result
