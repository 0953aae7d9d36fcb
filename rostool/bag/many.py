"""Several bags at once: expanding directories into bags, and running one job per bag in parallel processes.

A directory that is a rosbag2 bag (it has metadata.yaml, or holds only the .mcap/.db3 files of one split
bag) is one bag; any other directory is searched (recursively) for bags: .bag/.mcap/.db3 files and
rosbag2 directories. Results come back in the order of the bags (as given; a directory's bags sorted by
path), however the processes finish. One progress bar on stderr when it is a terminal.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TypeVar

from rostool.bag.formats import FILE_SUFFIXES, storage_kind
from rostool.bag.rosbag2_metadata import METADATA
from rostool.errors import RostoolError

_SPLIT = re.compile(r"^(.*)_\d+$")
T = TypeVar("T")


@dataclass(frozen=True)
class BagItem:
    path: Path | Any  # a local path, or a remote.RemotePath (object storage: copied locally by `call`)
    name: str  # unique among the bags of one command, safe as a hive partition value
    piece: int = 0  # a big bag's work cut in `pieces` (bag export): this item's share
    pieces: int = 1


def is_one_bag(path: Path) -> bool:
    """A directory that is itself a bag: rosbag2's metadata.yaml, or storage files of one split bag."""
    if (path / METADATA).exists():
        return True
    entries = list(path.iterdir())
    if any(entry.is_dir() or entry.suffix == ".bag" for entry in entries):
        return False
    storage = [entry for entry in entries if storage_kind(entry)]
    if not storage:
        return True  # not a bag either: the reader says so in one line
    if len(storage) == 1:
        return True
    prefixes = {(match.group(1) if (match := _SPLIT.match(entry.stem)) else entry.stem) for entry in storage}
    return len(prefixes) == 1 and len({entry.suffix for entry in storage}) == 1


def expand(paths: Sequence[str | Path]) -> list[BagItem]:
    """The bags that PATHs name, in order; names unique (the file stem, or the path below a directory)."""
    try:
        return _expand(paths)
    except OSError as err:
        raise RostoolError(f"{err.filename or paths[0]}: cannot read: {err.strerror or err}") from err


def _expand(paths: Sequence[str | Path]) -> list[BagItem]:
    from rostool.bag import remote

    found: list[tuple[Any, str]] = []
    for given in paths:
        if remote.is_remote(given):
            base = remote.resolve(str(given))
            bags = remote.list_bags(base)
            for bag in bags:
                relative = bag.path[len(base.path.rstrip("/")) + 1 :] if bag is not base else bag.name
                found.append((bag, _name(Path(relative or bag.name))))
            continue
        path = Path(given)
        if not path.exists():
            raise RostoolError(f"{path}: no such file or directory")
        if path.is_dir() and not is_one_bag(path):
            inside = sorted(_walk(path))
            if not inside:
                raise RostoolError(f"{path}: no bags in this directory (.bag, .mcap, .db3 or rosbag2 dirs)")
            found.extend((bag, _name(bag.relative_to(path))) for bag in inside)
        else:
            found.append((path, _name(Path(path.parent.name if path.name == METADATA else path.name))))
    names = [name for _, name in found]
    items = []
    for path, name in found:
        if names.count(name) > 1:  # same stem twice (a/run.bag, b/run.bag given one by one)
            name = _name(Path(str(path).strip("/")))
        items.append(BagItem(path, name))
    return items


def _walk(directory: Path) -> Iterator[Path]:
    for entry in directory.iterdir():
        if entry.is_dir():
            storage = any(storage_kind(p) for p in entry.iterdir())
            if (entry / METADATA).exists() or (storage and is_one_bag(entry)):
                yield entry
            else:
                yield from _walk(entry)
        elif entry.suffix in FILE_SUFFIXES:
            yield entry


def _name(relative: Path) -> str:
    stem = relative.with_suffix("") if relative.suffix in FILE_SUFFIXES else relative
    return re.sub(r"[^A-Za-z0-9_.-]", "_", str(stem).replace("/", "__")) or "bag"


PARALLEL_FROM_BYTES = 64 * 1024 * 1024


def _size(path: Path | Any) -> int:
    if not isinstance(path, Path):
        return 0  # in object storage: not worth a listing
    try:
        if path.is_dir():
            return sum(entry.stat().st_size for entry in path.rglob("*") if entry.is_file())
        return path.stat().st_size
    except OSError:
        return 0


def default_jobs() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


@dataclass
class Failure:
    message: str
    exit_code: int = 1


Work = Callable[[BagItem], T]  # one bag's job: a module-level function (it may run in another process)
Results = Iterator[tuple[BagItem, T | Failure]]  # each bag with its job's result, in the bags' order


def call(func: Work[T], item: BagItem) -> T | Failure:
    """func(item), or the Failure its one-line error describes. A bag in object storage is first copied into
    a local temporary directory (removed after), and errors name it by its URI."""
    try:
        if isinstance(item.path, Path):
            return func(item)
        from rostool.bag.remote import local_copy

        with local_copy(item.path) as local:
            try:
                return func(replace(item, path=local))
            except RostoolError as err:
                raise RostoolError(str(err).replace(str(local), str(item.path)), err.exit_code) from err
    except RostoolError as err:
        return Failure(str(err), err.exit_code)


_busy = False  # in a worker process: a bag is being processed
_interrupted = False


def _worker_init() -> None:
    signal.signal(signal.SIGINT, _on_sigint)


def _on_sigint(signum: int, frame: object) -> None:
    """Ctrl+C reaches the workers too (and the parent forwards it): a busy worker stops its bag, which
    removes its partial files; an idle one ignores it (no traceback from the pool's own loop)."""
    global _interrupted
    if _busy and not _interrupted:
        _interrupted = True
        raise KeyboardInterrupt


def _worker_call(func: Work[T], item: BagItem) -> T | Failure:
    global _busy, _interrupted
    _busy, _interrupted = True, False
    try:
        return call(func, item)
    except KeyboardInterrupt:
        return Failure("interrupted", 130)
    finally:
        _busy = False


def run(
    func: Work[T], items: Sequence[BagItem], jobs: int | None, label: str = "bags", bar: bool = True
) -> Results[T]:
    """(item, func(item) or its Failure) for every bag, in the order of `items`. `func` must be a module-level
    function (it runs in worker processes when jobs > 1)."""
    if jobs is None:  # starting worker processes costs ~0.5 s: worth it only for enough data
        jobs = default_jobs() if sum(_size(item.path) for item in items) >= PARALLEL_FROM_BYTES else 1
    with _Progress(len(items), label, bar) as progress:
        if jobs <= 1 or len(items) <= 1:
            for item in items:
                result = call(func, item)
                progress.advance()
                yield item, result
            return
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        context = multiprocessing.get_context("forkserver")
        module = getattr(getattr(func, "func", func), "__module__", __name__)  # func may be a partial
        context.set_forkserver_preload(["rostool.bag.reader", module])
        pool = ProcessPoolExecutor(min(jobs, len(items)), mp_context=context, initializer=_worker_init)
        futures = []
        try:
            futures = [pool.submit(_worker_call, func, item) for item in items]
            for future in futures:
                future.add_done_callback(lambda _f: progress.advance())
            for item, future in zip(items, futures, strict=True):
                yield item, future.result()
        except BaseException:  # Ctrl+C, or a failure that ends the command: stop the busy workers
            for future in futures:
                future.cancel()
            for process in list((getattr(pool, "_processes", None) or {}).values()):
                with contextlib.suppress(OSError):
                    os.kill(process.pid, signal.SIGINT)
            pool.shutdown(wait=True, cancel_futures=True)
            raise
        pool.shutdown()


class _Progress:
    """One rich progress bar over the bags on a terminal; nothing otherwise."""

    def __init__(self, total: int, label: str, show: bool) -> None:
        self.total = total
        self.label = label
        self.show = show
        self._bar: Any = None
        self._task: Any = None

    def __enter__(self) -> _Progress:
        if self.show and self.total > 1 and sys.stderr.isatty():
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            self._bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                console=Console(stderr=True),
                transient=True,
                redirect_stdout=False,  # stdout is the data (echo): never through the console
            )
            self._bar.start()
            self._task = self._bar.add_task(self.label, total=self.total)
        return self

    def advance(self) -> None:
        if self._bar is not None:
            self._bar.advance(self._task)

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()


def successes(
    func: Work[T],
    items: Sequence[BagItem],
    jobs: int | None,
    label: str = "bags",
    keep_going: bool = False,
    bar: bool = True,
    runner: Callable[..., Results[T]] | None = None,
) -> Iterator[tuple[BagItem, T]]:
    """`run`, keeping what succeeded. The first failure (in the bags' order) is the command's one-line
    error and ends the other workers; with `keep_going` each failure is one line on stderr as it comes,
    the other bags go on, and a last line ends the command with a non-zero exit."""
    failed: set[str] = set()
    bags = len({item.name for item in items})  # an item may be one piece of a bag (BagItem.pieces)
    results = (runner or run)(func, items, jobs, label, bar)  # runner: another engine (ray_engine.runner)
    try:
        for item, result in results:
            if not isinstance(result, Failure):
                yield item, result
            elif result.exit_code == 130:  # a worker stopped by Ctrl+C: end as quietly as the parent does
                raise KeyboardInterrupt
            elif not keep_going or bags == 1:
                raise RostoolError(result.message, result.exit_code)
            elif item.name not in failed:
                import click

                failed.add(item.name)
                click.echo(f"rostool: warning: skipped {item.path}: {result.message}", err=True)
    finally:
        results.close()
    if failed:
        raise RostoolError(f"{len(failed)} of {bags} bags failed (see the warnings above)")
