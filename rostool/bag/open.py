"""Input detection: what a path given on the command line is (by content, not by name).

rosbags picks a reader from the file suffix and fails with messages about suffixes; users pass files with
any name, rosbag2 directories without metadata.yaml, or metadata.yaml itself, so this looks at the magic
bytes (`formats.sniff`) and the directory contents and says clearly what is wrong when it is not a bag.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from rostool.bag.failures import warn
from rostool.bag.formats import (
    FORMATS,
    HEAD_SIZE,
    ROS1_PREFIX,
    ZSTD_MAGIC,
    by_storage,
    kind_of,
    sniff,
    storage_kind,
)
from rostool.bag.model import BagInput, BagKind
from rostool.bag.rosbag2_metadata import METADATA, MetadataError, check_metadata, load_metadata
from rostool.errors import RostoolError


def detect(given: str | Path) -> BagInput:
    """Classify `given`; raises RostoolError with one clear line when it is not a readable bag."""
    from rostool.bag.bounded import install

    install()  # whatever reads the bag next inflates no chunk past its declared size
    path = Path(given)
    if not path.exists():
        raise RostoolError(f"{path}: no such file or directory")
    if path.is_file() and path.name == METADATA:
        path = path.parent
    if path.is_dir():
        try:
            return _detect_directory(path)
        except OSError as err:
            raise RostoolError(f"{err.filename or path}: cannot read: {err.strerror or err}") from err
    if not path.is_file():
        raise RostoolError(f"{path}: not a regular file, not a bag")
    try:
        size = path.stat().st_size
        if size == 0:
            raise RostoolError(f"{path}: empty file (0 bytes), not a bag")
        with path.open("rb") as handle:
            head = handle.read(HEAD_SIZE)
    except PermissionError as err:
        raise RostoolError(f"{path}: permission denied") from err
    except OSError as err:
        raise RostoolError(f"{path}: cannot read: {err.strerror or err}") from err
    kind = kind_of(head)
    if kind == "bag":
        if not head.startswith(FORMATS["bag"].magic):
            version = head[len(ROS1_PREFIX) :].split(b"\n")[0].decode(errors="replace")
            raise RostoolError(f"{path}: ROS 1 bag version {version} is not supported (only 2.0)")
        return BagInput(path, "bag", (path,), "bag")
    if kind is not None:
        return BagInput(path, kind, (path,), FORMATS[kind].storage)
    if head.startswith(ZSTD_MAGIC):
        raise RostoolError(
            f"{path}: a zstd-compressed storage file; pass the rosbag2 directory that contains it"
        )
    raise RostoolError(f"{path}: not a bag (expected a ROS 1 .bag, an .mcap or .db3 file, or a rosbag2 dir)")


def _detect_directory(path: Path) -> BagInput:
    metadata = path / METADATA
    problem = ""
    if metadata.is_file():
        try:
            body = load_metadata(metadata)
            storage, files = check_metadata(body, metadata)
        except MetadataError as err:
            problem = err.problem
        else:
            if str(body.get("compression_mode") or "").lower() != "file":
                kind = by_storage(storage).kind
                for file in files:
                    if file.stat().st_size == 0 or sniff(file) != kind:
                        raise RostoolError(
                            f"{file}: not a valid {kind} file (metadata.yaml: storage {storage})"
                        )
            return BagInput(path, "rosbag2", tuple(files), storage, metadata)
    elif metadata.exists():
        problem = "not a file"
    found = sorted(p for p in path.iterdir() if storage_kind(p) and p.is_file())
    if not found:
        if problem:
            raise MetadataError(metadata, f"{problem}; and no .mcap/.db3 files beside it to read instead")
        raise RostoolError(f"{path}: directory has no metadata.yaml and no .mcap/.db3 files, not a bag")
    kinds = {storage_kind(p) for p in found}
    if len(kinds) > 1:
        why = f"{metadata}: {problem}; and" if problem else f"{path}: directory without metadata.yaml"
        raise RostoolError(f"{why} mixes .mcap and .db3 files")
    kind: BagKind = "mcap" if kinds == {"mcap"} else "db3"
    for file in found:
        if file.stat().st_size == 0 or sniff(file) != kind:
            prefix = f"{metadata}: {problem}; and " if problem else ""
            raise RostoolError(f"{prefix}{file}: not a valid {kind} file")
    if problem:
        warn(fallback_warning(metadata, problem, found))
    return BagInput(path, kind, tuple(found), FORMATS[kind].storage)


def fallback_warning(metadata: Path, problem: str, files: Sequence[Path]) -> str:
    listed = files[0].name if len(files) == 1 else f"{len(files)} {files[0].suffix} files"
    return f"{metadata}: {problem}; reading {listed} beside it instead"
