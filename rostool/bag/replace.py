"""`--force`: what an output may replace, and replacing it with no moment where neither copy exists.

--force replaces only a bag rostool could have written there: a file named .bag/.mcap/.db3 (or .active,
.zstd, what a recorder leaves) or starting like a bag, or a directory holding nothing else (a rosbag2
directory: metadata.yaml and storage files). Never an input, never a directory holding an input, never
anything else (a user's notes, a source tree): those are refused in one line, and the user removes them
if that is really meant.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterable
from pathlib import Path

from rostool.bag.formats import FILE_SUFFIXES, FILES, ZSTD_MAGIC
from rostool.bag.rosbag2_metadata import METADATA, METADATA_TMP
from rostool.errors import RostoolError

_MAGICS = (*(fmt.magic for fmt in FILES), ZSTD_MAGIC)  # zstd: NAME_0.mcap.zstd, a file-compressed storage
_DIR_FILES = {METADATA, METADATA_TMP}
_SUFFIXES = (*FILE_SUFFIXES, ".active", ".zstd")  # .active: what a recorder is writing


def is_bag_file(path: Path) -> bool:
    """A regular file named or starting like a bag (an empty one too: a recorder killed at once)."""
    if path.is_symlink() or not path.is_file():
        return False
    if path.name.lower().endswith(_SUFFIXES):
        return True
    try:
        with path.open("rb") as handle:
            head = handle.read(16)
    except OSError:
        return False
    return head == b"" or any(head.startswith(magic) for magic in _MAGICS)


def is_bag_dir(path: Path) -> bool:
    """A directory of bag files, metadata.yaml and `.active` directories of the same, nothing else."""
    if path.is_symlink() or not path.is_dir():
        return False
    try:
        entries = list(path.iterdir())
    except OSError:
        return False
    for entry in entries:
        if entry.name in _DIR_FILES and entry.is_file() and not entry.is_symlink():
            continue
        if entry.name.endswith(".active") and is_bag_dir(entry):
            continue
        if not is_bag_file(entry):
            return False
    return True


def check_replaceable(path: Path, inputs: Iterable[Path] = ()) -> None:
    """Raise unless --force may replace `path`: no input is, or is inside, it; and it is a bag."""
    if not (path.exists() or path.is_symlink()):
        return
    target = path.resolve()
    for given in inputs:
        source = given.resolve()
        if source == target or target in source.parents:
            raise RostoolError(f"{path}: it is or holds the input {given}; --force never replaces an input")
    if path.is_symlink() or not (is_bag_file(path) or is_bag_dir(path)):
        raise RostoolError(
            f"{path} exists and is not a bag rostool could have written; --force replaces only such bags: "
            f"choose another name, or remove it yourself"
        )


def remove_bag(path: Path) -> None:
    """Delete what `check_replaceable` accepted."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def swap_into_place(produced: Path, target: Path) -> None:
    """Move `produced` to `target`; an old `target` is first moved to a hidden sibling, then deleted, so
    a crash at any moment leaves the old or the new bag under a name."""
    if not (target.exists() or target.is_symlink()):
        os.replace(produced, target)
        return
    aside = target.with_name(f".{target.name}.rostool-old-{os.getpid()}")
    os.replace(target, aside)
    try:
        os.replace(produced, target)
    except OSError:
        os.replace(aside, target)
        raise
    remove_bag(aside)
