"""`bag reindex DIR`: a rosbag2 directory gets a metadata.yaml that matches its storage files again.

For what a killed `bag record` leaves (`NAME.mcap.active/`, `NAME.db3.active/`: storage files, no
metadata.yaml) and for directories whose metadata.yaml is lost or stale, as `ros2 bag reindex` does.
"""

from __future__ import annotations

import errno
import os
import shutil
import sqlite3
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostool.bag.open import STORAGE_SUFFIXES, check_metadata, guard, load_metadata, sniff
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.bag.reindex import ReindexResult

METADATA_VERSION = 8  # what `bag record` writes (rosbags' writer, version=8)


def reindex_rosbag2(given: Path) -> ReindexResult:
    from rostool.bag.reindex import ReindexResult

    directory = given.parent if given.name == "metadata.yaml" else given
    files = sorted(p for p in directory.iterdir() if p.suffix in STORAGE_SUFFIXES and p.is_file())
    kinds = {sniff(p) if p.stat().st_size else None for p in files}
    if not files:
        raise RostoolError(f"{directory}: no .mcap or .db3 storage files to reindex")
    if len(kinds) != 1 or kinds.pop() not in ("mcap", "db3"):
        raise RostoolError(f"{directory}: its storage files are not all .mcap or all .db3 files")
    kind = STORAGE_SUFFIXES[files[0].suffix]
    if any(STORAGE_SUFFIXES[p.suffix] != kind or sniff(p) != kind for p in files):
        raise RostoolError(f"{directory}: its storage files are not all valid {kind} files")
    if _complete(directory, files):
        raise RostoolError(
            f"{directory}: reindex works on a ROS 1 .bag, an .mcap file or a rosbag2 directory cut short "
            "(no usable metadata.yaml, or storage without its summary); this one is complete"
        )
    backup = directory.with_name(directory.name + ".orig")
    if backup.exists():
        raise RostoolError(f"{backup} exists (from an earlier reindex?); move it away first")
    partial = changed = False
    try:
        _keep_originals(directory, backup, copy_db3=kind == "db3")
        for path in files:
            if kind == "mcap":
                repaired = _repair_mcap(path)
                partial, changed = partial or repaired, changed or repaired
            else:
                changed = True
                _roll_back(path)
        messages = _write_metadata(directory, files, kind)
    except OSError as err:
        if not changed:
            shutil.rmtree(backup, ignore_errors=True)
        if err.errno not in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
            raise
        kept = f"the originals are in {backup}" if changed else "nothing was changed"
        raise RostoolError(
            f"{directory}: no room to rebuild it ({err.strerror}); {kept}: free some space and retry"
        ) from err
    return ReindexResult(directory, backup, messages, 0, partial)


def _complete(directory: Path, files: list[Path]) -> bool:
    from rostool.bag.reindex import mcap_complete

    metadata = directory / "metadata.yaml"
    if not metadata.is_file():
        return False
    try:
        _storage, listed = check_metadata(load_metadata(metadata), metadata)
    except RostoolError:
        return False
    if sorted(listed) != files or any(p.with_name(p.name + "-journal").exists() for p in files):
        return False
    return all(mcap_complete(p) for p in files if p.suffix == ".mcap")


def _keep_originals(directory: Path, backup: Path, copy_db3: bool) -> None:
    """Hard links keep the originals of files that are replaced, never changed in place; a .db3 whose
    journal will be rolled back into it is copied."""
    backup.mkdir()
    for path in sorted(directory.iterdir()):
        if not path.is_file():
            continue
        target = backup / path.name
        if copy_db3 and path.suffix == ".db3":
            shutil.copy2(path, target)
            continue
        try:
            os.link(path, target)
        except OSError:
            shutil.copy2(path, target)


def _repair_mcap(path: Path) -> bool:
    """Rewrite an .mcap cut short (no footer) with every complete record; True when it was cut short."""
    from rostool.bag.reindex import mcap_complete, reindex_mcap

    if mcap_complete(path):
        return False
    tmp = path.with_name(f".{path.name}.reindex-{os.getpid()}")
    try:
        reindex_mcap(path, tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return True


def _roll_back(path: Path) -> None:
    """Opening the database read-write rolls back the transaction its killed writer left unfinished."""
    try:
        with sqlite3.connect(path) as conn:
            (verdict,) = conn.execute("PRAGMA quick_check").fetchone()
            conn.execute("SELECT count(*) FROM messages").fetchone()
        conn.close()
    except sqlite3.Error as err:
        raise RostoolError(f"{path}: cannot repair the database: {err}") from err
    if verdict != "ok":
        raise RostoolError(f"{path}: the database is damaged beyond a rollback: {verdict}")


def _write_metadata(directory: Path, files: list[Path], kind: str) -> int:
    from rosbags.interfaces import ConnectionExtRosbag2
    from rosbags.rosbag2.metadata import dump_qos_v8
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

    topics: dict[tuple[str, str], dict[str, Any]] = {}
    entries = []
    start_all, end_all = 2**63 - 1, 0
    for path in files:
        storage = McapReader(path) if kind == "mcap" else Sqlite3Reader(path)
        with guard(path):
            storage.open()
            try:
                count = 0
                for conn in storage.connections:
                    ext = conn.ext
                    key = (conn.topic, conn.msgtype)
                    entry = topics.get(key)
                    if entry is None:
                        qos = ext.offered_qos_profiles if isinstance(ext, ConnectionExtRosbag2) else []
                        entry = topics[key] = {
                            "topic_metadata": {
                                "name": conn.topic,
                                "type": conn.msgtype,
                                "serialization_format": getattr(ext, "serialization_format", "cdr"),
                                "offered_qos_profiles": dump_qos_v8(qos),
                                "type_description_hash": conn.digest or "",
                            },
                            "message_count": 0,
                        }
                    entry["message_count"] += conn.msgcount
                    count += conn.msgcount
                start, end = storage.metadata.start_time, storage.metadata.end_time
            finally:
                storage.close()
        if count:
            start_all, end_all = min(start_all, start), max(end_all, end)
        else:
            start, end = 0, 0
        entries.append(_span(path.name, start, end, count))
    total = sum(entry["message_count"] for entry in topics.values())
    if not total:
        start_all = end_all = 0
    body = {
        "version": METADATA_VERSION,
        "storage_identifier": "mcap" if kind == "mcap" else "sqlite3",
        "relative_file_paths": [path.name for path in files],
        **_span("", start_all, end_all, total),
        "topics_with_message_count": list(topics.values()),
        "compression_format": "",
        "compression_mode": "",
        "files": entries,
        "custom_data": None,
        "ros_distro": "rostool",
    }
    body.pop("path")
    _dump(directory / "metadata.yaml", {"rosbag2_bagfile_information": body})
    return total


def _span(name: str, start: int, end: int, count: int) -> dict[str, Any]:
    return {
        "path": name,
        "starting_time": {"nanoseconds_since_epoch": start},
        "duration": {"nanoseconds": max(0, end - start)},
        "message_count": count,
    }


def _dump(path: Path, data: dict[str, Any]) -> None:
    import yaml

    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(yaml.safe_dump(data, default_flow_style=False, sort_keys=False))
    os.replace(tmp, path)
