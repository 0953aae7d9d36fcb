"""`bag export` of one bag or many: each bag exported on its own (in local processes or Ray tasks) and the
results summed. How the work is spread follows its estimated cost (export_cost.py), not only its bytes: worker
processes when there is enough of it, and a big indexed .mcap cut into runs of chunks exported in parallel,
whose tables are then joined byte-wise (parquet_concat.py) into the files one export writes. Into object
storage each bag is written to a local folder first, uploaded when complete."""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import replace
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
    piece_bytes: int | None = None,
) -> tuple[ExportResult, int]:
    """The sum of what was exported, and of how many bags (fewer than given with `keep_going`).
    `piece_bytes`: cut every .mcap of at least that many bytes in as many pieces as workers (0: none), instead
    of the estimated cost's rule (`plan`)."""
    from rostool.bag.export import join_pieces
    from rostool.bag.many import successes

    several = len(items) > 1
    total = ExportResult("")
    exported = 0
    work = partial(_export_one, options, several, remote_out)
    jobs, cut = plan(items, options, remote_out, jobs, runner is not None, piece_bytes)
    done: dict[str, list[tuple[int, ExportResult]]] = {}  # a cut bag's pieces exported so far
    unfinished = {item.name for item in cut if item.pieces > 1}
    try:
        for item, result in successes(work, cut, jobs, "exporting", keep_going, runner=runner):
            if item.pieces > 1:
                done.setdefault(item.name, []).append((item.piece, result))
                if len(done[item.name]) < item.pieces:
                    continue
                pieces = [piece for _k, piece in sorted(done.pop(item.name), key=lambda pair: pair[0])]
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


def plan(
    items: Sequence[BagItem],
    options: ExportOptions,
    remote_out: Any,
    jobs: int | None,
    ray: bool,
    piece_bytes: int | None = None,
) -> tuple[int | None, list[BagItem]]:
    """The local jobs and the work: each bag, or its pieces. The rule (export_cost.py estimates seconds of
    one core): without -j, worker processes when the whole costs at least PARALLEL_FROM (or weighs
    many.PARALLEL_FROM_BYTES); a bag is cut (an indexed local .mcap, Parquet tables, no images) into as
    many pieces as its share of the work holds PIECE_SECONDS, at most one per worker: with as many bags as
    workers or more, none is cut unless it outweighs the others. With several workers the work comes the
    costliest first: the last to start are the shortest, so every worker stays busy to the end."""
    from rostool.bag import export_cost
    from rostool.bag.many import default_jobs

    sizes = [_mcap_bytes(item.path) for item in items]
    costs = [export_cost.seconds(item.path, options.topics) for item in items]
    if jobs is None and not ray and sum(costs) >= export_cost.PARALLEL_FROM:
        jobs = default_jobs()  # else many.run's rule by bytes (images cost more than their estimate)
    workers = jobs or default_jobs()
    if workers < 2:
        return jobs, list(items)
    if options.fmt != "parquet" or options.images is not None or remote_out is not None:
        return jobs, _largest_first(list(zip(items, costs, strict=True)))
    work: list[tuple[BagItem, float]] = []
    share = max(export_cost.PIECE_SECONDS, sum(costs) / (2 * workers))
    for item, size, cost in zip(items, sizes, costs, strict=True):
        if piece_bytes is not None:
            pieces = min(workers, size // piece_bytes) if piece_bytes > 0 else 1
        else:
            pieces = min(workers, int(cost // share)) if size else 1
        pieces = max(1, pieces)
        work.extend((replace(item, piece=k, pieces=pieces), cost / pieces) for k in range(pieces))
    return jobs, _largest_first(work)


def _largest_first(work: list[tuple[BagItem, float]]) -> list[BagItem]:
    """The items by estimated cost, the largest first (a stable sort: a cut bag's pieces stay in order)."""
    return [item for item, _cost in sorted(work, key=lambda pair: -pair[1])]


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
        with fewer_collections():
            return export_bag(item.path, options, partition=partition, progress=progress, piece=piece)
    import tempfile

    from rostool.bag.remote import upload

    with tempfile.TemporaryDirectory(prefix="rostool-export-") as stage:
        with fewer_collections():
            result = export_bag(
                item.path, replace(options, out=Path(stage)), partition=partition, progress=progress
            )
        result.files = upload(Path(stage), remote_out)
    return result


YOUNG_COLLECTION_FROM = 50_000  # allocations (Python's default: 700)


@contextmanager
def fewer_collections() -> Iterator[None]:
    """Python's cyclic garbage collector, made cheap for one export. A batch of decoded messages (a type
    decoded one by one: millions of small objects) outlives young collections, so with the default
    thresholds full collections kept coming, each walking every object of the process: more than 40 % of
    the CPU of exporting tf2_msgs/TFMessage, and more in a Ray worker, whose imports hold twice the
    objects of a local one. So: what exists now is frozen (never walked again) and young collections wait
    for 50,000 allocations; the export's own garbage is freed by reference counting (no cycles)."""
    thresholds = gc.get_threshold()
    gc.collect()
    gc.freeze()
    gc.set_threshold(YOUNG_COLLECTION_FROM, *thresholds[1:])
    try:
        yield
    finally:
        gc.set_threshold(*thresholds)
        gc.unfreeze()
