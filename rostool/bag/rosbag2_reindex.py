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
from typing import Any

from rostool.bag.failures import guard
from rostool.bag.mcap_reindex import mcap_complete, rebuild_mcap
from rostool.bag.model import BagFormat, ReindexResult
from rostool.bag.rosbag2_metadata import METADATA, check_metadata, load_metadata, write_metadata
from rostool.errors import RostoolError

METADATA_VERSION = 8  # what `bag record` writes (rosbags' writer, version=8)


def reindex_rosbag2(directory: Path, files: list[Path], fmt: BagFormat) -> ReindexResult:
    """Repair DIR whose storage `files` (all of format `fmt`, as `reindex` found them) lost their
    metadata.yaml or were cut short."""
    if _complete(directory, files, fmt):
        raise RostoolError(
            f"{directory}: reindex works on a ROS 1 .bag, an .mcap file or a rosbag2 directory cut short "
            "(no usable metadata.yaml, or storage without its summary); this one is complete"
        )
    backup = directory.with_name(directory.name + ".orig")
    if backup.exists():
        raise RostoolError(f"{backup} exists (from an earlier reindex?); move it away first")
    partial = changed = False
    try:
        _keep_originals(directory, backup, copied=set(files) if fmt.kind == "db3" else set())
        for path in files:
            if fmt.kind == "mcap":
                repaired = _repair_mcap(path)
                partial, changed = partial or repaired, changed or repaired
            else:
                changed = True
                _roll_back(path)
        messages = _write_metadata(directory, files, fmt)
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


def _complete(directory: Path, files: list[Path], fmt: BagFormat) -> bool:
    metadata = directory / METADATA
    if not metadata.is_file():
        return False
    try:
        _storage, listed = check_metadata(load_metadata(metadata), metadata)
    except RostoolError:
        return False
    if sorted(listed) != files or any(p.with_name(p.name + "-journal").exists() for p in files):
        return False
    return fmt.kind != "mcap" or all(mcap_complete(p) for p in files)


def _keep_originals(directory: Path, backup: Path, copied: set[Path]) -> None:
    """Hard links keep the originals of files that are replaced, never changed in place; the `copied`
    ones (a .db3 whose journal will be rolled back into it) are copied."""
    backup.mkdir()
    for path in sorted(directory.iterdir()):
        if not path.is_file():
            continue
        target = backup / path.name
        if path in copied:
            shutil.copy2(path, target)
            continue
        try:
            os.link(path, target)
        except OSError:
            shutil.copy2(path, target)


def _repair_mcap(path: Path) -> bool:
    """Rewrite an .mcap cut short (no footer) with every complete record; True when it was cut short."""
    if mcap_complete(path):
        return False
    tmp = path.with_name(f".{path.name}.reindex-{os.getpid()}")
    try:
        rebuild_mcap(path, tmp)
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


def _write_metadata(directory: Path, files: list[Path], fmt: BagFormat) -> int:
    from rosbags.interfaces import ConnectionExtRosbag2
    from rosbags.rosbag2.metadata import dump_qos_v8

    topics: dict[tuple[str, str], dict[str, Any]] = {}
    entries = []
    start_all, end_all = 2**63 - 1, 0
    for path in files:
        storage = fmt.reader(path)
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
        "storage_identifier": fmt.storage,
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
    write_metadata(directory, body)
    return total


def _span(name: str, start: int, end: int, count: int) -> dict[str, Any]:
    return {
        "path": name,
        "starting_time": {"nanoseconds_since_epoch": start},
        "duration": {"nanoseconds": max(0, end - start)},
        "message_count": count,
    }
