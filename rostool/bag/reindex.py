"""`bag reindex`: make a bag whose writer died readable again (rosbags has no reindexing; written here).

A single file is rebuilt by its format's `rebuild` in the format table (`ros1_reindex`: every chunk and
the complete records of a half-written last one, with fresh index records; `mcap_reindex`: every readable
record copied into a file whose writer adds the summary and indexes) into a new file that then takes its
place; the original is kept as `NAME.orig.bag` / `NAME.orig.mcap`, as `rosbag reindex` does.
A rosbag2 directory (also `NAME.mcap.active/` or `NAME.db3.active/` left by a killed `bag record`) is
repaired as `ros2 bag reindex` does (`rosbag2_reindex`), its original files kept in `DIR.orig/`.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

from rostool.bag.formats import FILES, FORMATS, STORAGES, sniff, storage_kind
from rostool.bag.model import BagFormat, ReindexResult
from rostool.bag.open import detect
from rostool.bag.rosbag2_metadata import METADATA
from rostool.bag.rosbag2_reindex import reindex_rosbag2
from rostool.errors import RostoolError

_REBUILT_SUFFIXES = tuple(fmt.suffix for fmt in FILES if fmt.rebuild is not None)  # .bag, .mcap


def backup_path(path: Path) -> Path:
    """NAME.orig.bag / NAME.orig.mcap beside a rebuilt file (any other name gets `.orig.bag` added)."""
    suffix = path.suffix if path.suffix in _REBUILT_SUFFIXES else ""
    return path.with_name(f"{path.name.removesuffix(suffix)}.orig{suffix or '.bag'}")


def reindex(given: str | Path) -> ReindexResult:
    if Path(given).is_dir() or Path(given).name == METADATA:
        directory = Path(given).parent if Path(given).name == METADATA else Path(given)
        return reindex_rosbag2(directory, *_storage_files(directory))
    bag = detect(given)
    rebuild = FORMATS[bag.kind].rebuild
    if rebuild is None or len(bag.files) != 1 or bag.path.is_dir():
        raise RostoolError(f"{bag.path}: reindex works on a ROS 1 .bag or a single .mcap file")
    path = bag.path
    backup = backup_path(path)
    if backup.exists():
        raise RostoolError(f"{backup} exists (from an earlier reindex?); move it away first")
    tmp = path.with_name(f".{path.name}.reindex-{os.getpid()}")
    try:
        messages, chunks, partial = rebuild(path, tmp)
        os.replace(path, backup)
        os.replace(tmp, path)
    except BaseException as err:
        tmp.unlink(missing_ok=True)
        if isinstance(err, OSError) and err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
            raise RostoolError(
                f"{path}: no room for the rebuilt copy ({err.strerror}); the file is untouched: free some "
                "space and retry"
            ) from err
        raise
    return ReindexResult(path, backup, messages, chunks, partial)


def _storage_files(directory: Path) -> tuple[list[Path], BagFormat]:
    """The storage files of a rosbag2 directory, checked to be all of one format (by name and content)."""
    files = sorted(p for p in directory.iterdir() if storage_kind(p) and p.is_file())
    kinds = {sniff(p) if p.stat().st_size else None for p in files}
    if not files:
        raise RostoolError(f"{directory}: no .mcap or .db3 storage files to reindex")
    if len(kinds) != 1 or kinds.pop() not in {fmt.kind for fmt in STORAGES}:
        raise RostoolError(f"{directory}: its storage files are not all .mcap or all .db3 files")
    kind = storage_kind(files[0])
    if any(storage_kind(p) != kind or sniff(p) != kind for p in files):
        raise RostoolError(f"{directory}: its storage files are not all valid {kind} files")
    assert kind is not None
    return files, FORMATS[kind]
