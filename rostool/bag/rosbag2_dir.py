"""`ros2 bag record`'s output: a rosbag2 directory (metadata.yaml + NAME_0.mcap, NAME_1.mcap, ...).

Each storage file is written by `record.Ros2Sink` (rosbags' writer: mcap or sqlite3, message or file
compression with zstd) under `DIR/NAME_N.mcap.active/` and moved into DIR when it is closed; an
uncompressed .mcap is also linked as DIR/NAME_N.mcap while written, so after a crash `rostool bag reindex
DIR` finds it. A new file starts when the current one reaches --max-bag-size bytes or spans
--max-bag-duration seconds (rosbag2's splitting); --max-bag-files deletes the oldest. metadata.yaml
(version 9, rosbag2's keys) is rewritten after every closed file, so a recorder killed mid-way leaves a
readable bag of the files completed so far.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from rostool.bag.formats import by_storage
from rostool.bag.record_sinks import Ros2Sink
from rostool.bag.replace import check_replaceable, remove_bag
from rostool.bag.rosbag2_metadata import write_metadata
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.bag.storage_config import StorageConfig
    from rostool.graph.recording import RecordSource

Storage = Literal["mcap", "sqlite3"]


@dataclass
class Rosbag2Layout:
    path: Path
    storage: Storage = "mcap"
    max_size: int = 0  # bytes per file; 0: no splitting by size
    max_duration: float = 0.0  # seconds per file; 0: no splitting by duration
    max_files: int = 0  # 0: keep every file
    compression_mode: str = "none"  # none | file | message
    compression_format: str = ""  # zstd
    custom_data: dict[str, str] = field(default_factory=dict)
    storage_config: StorageConfig | None = None  # --storage-config-file


def check_output(path: Path) -> None:
    """ros2 bag record's rule: the output folder must not exist; its parent must be writable."""
    if path.exists():
        raise RostoolError(f"Output folder '{path}' already exists: choose another -o/--output or remove it")
    parent = path.parent
    if not parent.is_dir():
        raise RostoolError(f"{path}: cannot record: directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise RostoolError(f"{path}: cannot record: directory {parent} is not writable")


class Rosbag2DirSink:
    """The `Sink` of record.py for a rosbag2 directory, splitting into several storage files."""

    def __init__(self, layout: Rosbag2Layout, source: RecordSource, force: bool) -> None:
        self.layout = layout
        self.final = layout.path
        self.active = layout.path
        self.source = source
        self.problems: dict[str, str] = {}
        if force:  # only a bag: never a folder of the user's other files
            check_replaceable(layout.path)
            remove_bag(layout.path)
        check_output(layout.path)
        try:
            layout.path.mkdir()
        except OSError as err:
            raise RostoolError(f"{layout.path}: cannot create the bag: {err.strerror or err}") from err
        self._index = 0
        self._parts: list[dict[str, Any]] = []  # metadata of the closed files, oldest first
        self._done = 0  # bytes of the closed files still in the directory
        self._file_start: int | None = None
        self._sink: Ros2Sink = self._open_part()

    # -- files -----------------------------------------------------------------------------------
    def _open_part(self) -> Ros2Sink:
        layout = self.layout
        fmt = by_storage(layout.storage)
        name = f"{layout.path.name}_{self._index}{fmt.suffix}"
        compression = None
        if layout.compression_mode != "none":
            compression = (layout.compression_mode, layout.compression_format or "zstd")
        self._file_start = None
        sink = Ros2Sink(layout.path / name, fmt, self.source, False, compression, layout.storage_config)
        if fmt.kind == "mcap" and compression is None:
            # The file being written also appears as DIR/NAME_N.mcap (a second link to it): after a crash
            # it is where ros2 bag and `rostool bag reindex DIR` look for it.
            produced = sink.active / f"{sink.active.name}{fmt.suffix}"
            with contextlib.suppress(OSError):
                os.link(produced, sink.final)
        return sink

    def _close_part(self) -> None:
        sink = self._sink
        if sink.final.exists():  # the crash-time link: the closed file replaces it
            sink.final.unlink()
        sink.close()
        self.problems.update(sink.problems)
        meta = dict(sink.metadata)
        meta["relative_path"] = sink.final.name
        self._parts.append(meta)
        self._done += sink.final.stat().st_size
        max_files = self.layout.max_files
        while max_files and len(self._parts) > max_files:
            oldest = self._parts.pop(0)
            path = self.layout.path / oldest["relative_path"]
            self._done -= path.stat().st_size if path.exists() else 0
            path.unlink(missing_ok=True)
        self._write_metadata()

    @property
    def size(self) -> int:
        return self._done + self._sink.size

    def write(self, key: object, header: Mapping[str, str], time_ns: int, payload: bytes) -> bool:
        layout = self.layout
        if self._file_start is None:
            self._file_start = time_ns
        elif (layout.max_duration and time_ns - self._file_start >= layout.max_duration * 1e9) or (
            layout.max_size and self._sink.size >= layout.max_size
        ):
            self._close_part()
            self._index += 1
            self._sink = self._open_part()
            self._file_start = time_ns
        return self._sink.write(key, header, time_ns, payload)

    def split(self) -> None:
        """Start the next file now (rosbag2's split_bagfile service)."""
        self._close_part()
        self._index += 1
        self._sink = self._open_part()
        self._file_start = None

    def flush(self) -> None:
        self._sink.flush()

    def close(self) -> None:
        self._close_part()

    # -- metadata.yaml ---------------------------------------------------------------------------
    def _write_metadata(self) -> None:
        parts = self._parts
        starts = [int(p["starting_time"]["nanoseconds_since_epoch"]) for p in parts if p.get("message_count")]
        ends = [
            int(p["starting_time"]["nanoseconds_since_epoch"]) + int(p["duration"]["nanoseconds"])
            for p in parts
            if p.get("message_count")
        ]
        start = min(starts) if starts else 0
        topics: dict[str, dict[str, Any]] = {}
        for part in parts:
            for entry in part.get("topics_with_message_count") or []:
                name = entry["topic_metadata"]["name"]
                known = topics.setdefault(
                    name, {"topic_metadata": entry["topic_metadata"], "message_count": 0}
                )
                known["message_count"] += int(entry["message_count"])
        mode = self.layout.compression_mode
        info = {
            "version": 9,
            "storage_identifier": self.layout.storage,
            "duration": {"nanoseconds": (max(ends) - start) if ends else 0},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": sum(int(p.get("message_count", 0)) for p in parts),
            "topics_with_message_count": list(topics.values()),
            "compression_format": (self.layout.compression_format or "zstd") if mode != "none" else "",
            "compression_mode": mode.upper() if mode != "none" else "",
            "relative_file_paths": [p["relative_path"] for p in parts],
            "files": [
                {
                    "path": p["relative_path"],
                    "starting_time": p["starting_time"],
                    "duration": p["duration"],
                    "message_count": p.get("message_count", 0),
                }
                for p in parts
            ],
            "custom_data": dict(self.layout.custom_data),
            "ros_distro": os.environ.get("ROS_DISTRO") or "rostool",
        }
        write_metadata(self.layout.path, info)
