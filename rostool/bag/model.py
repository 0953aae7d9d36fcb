"""What bag/ knows of a bag, as data: the input a user named, the facts `bag info` reports, a reindex's
outcome, and the shape of one row of the format table (`formats.py`). Every module of bag/ may look down
here; nothing here reads a file."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

BagKind = Literal["bag", "rosbag2", "mcap", "db3"]
NS = 1_000_000_000


@dataclass(frozen=True)
class BagInput:
    """One bag as given by the user: a ROS 1 file, a rosbag2 directory, or bare storage file(s)."""

    path: Path
    kind: BagKind
    files: tuple[Path, ...]  # storage files (the .bag itself for ROS 1)
    storage: str  # `bag` for ROS 1, else the rosbag2 storage identifier: `mcap` or `sqlite3`
    metadata: Path | None = None  # metadata.yaml of a rosbag2 directory

    @property
    def ros_version(self) -> int:
        return 1 if self.kind == "bag" else 2

    @property
    def size(self) -> int:
        extra = [self.metadata] if self.metadata else []
        return sum(path.stat().st_size for path in (*self.files, *extra) if path.exists())


@dataclass
class TypeInfo:
    name: str  # as the format names it: `pkg/Name` for ROS 1, `pkg/msg/Name` for ROS 2
    hash: str = ""  # md5 for ROS 1, RIHS01 type hash for ROS 2 where stored


@dataclass
class TopicInfo:
    name: str
    type: str
    count: int
    connections: int = 1
    frequency: float | None = None  # Hz, from the median period (as `rosbag info --freq`)
    serialization: str = "cdr"  # ROS 2: the topic's serialization format


@dataclass
class BagInfo:
    path: str
    format: BagKind
    storage: str  # bag | mcap | sqlite3
    version: str
    size: int
    messages: int
    start_ns: int | None
    end_ns: int | None
    compression: str = "none"
    types: list[TypeInfo] = field(default_factory=list)
    topics: list[TopicInfo] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    chunk_sizes: tuple[int, int] | None = None  # (uncompressed, compressed) bytes when compressed
    note: str = ""
    ros_distro: str = ""  # ROS 2: the distro that recorded it, where stored

    @property
    def ros_version(self) -> int:
        return 1 if self.format == "bag" else 2

    @property
    def duration(self) -> float:
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / NS

    def to_dict(self) -> dict[str, Any]:
        """The `--json` object."""
        result: dict[str, Any] = {
            "path": self.path,
            "format": self.format,
            "storage": self.storage,
            "ros_version": self.ros_version,
            "version": self.version,
            "duration": self.duration,
            "start": None if self.start_ns is None else self.start_ns / NS,
            "end": None if self.end_ns is None else self.end_ns / NS,
            "size": self.size,
            "messages": self.messages,
            "compression": self.compression,
            "types": [{"name": t.name, "hash": t.hash} for t in self.types],
            "topics": [_topic_dict(t) for t in self.topics],
        }
        if self.files:
            result["files"] = self.files
        return result


def _topic_dict(topic: TopicInfo) -> dict[str, Any]:
    entry: dict[str, Any] = {"name": topic.name, "type": topic.type, "count": topic.count}
    if topic.connections > 1:
        entry["connections"] = topic.connections
    if topic.frequency is not None:
        entry["frequency"] = topic.frequency
    return entry


@dataclass
class ReindexResult:
    path: Path
    backup: Path
    messages: int
    chunks: int
    partial: bool  # messages were recovered from a half-written last chunk


# (damaged file, new file) -> (messages, chunks, partial)
Rebuild = Callable[[Path, Path], tuple[int, int, bool]]


@dataclass(frozen=True)
class BagFormat:
    """One row of the format table: what a format is, and the functions that serve it."""

    kind: BagKind
    label: str  # how `bag info` names it
    storage: str  # rosbag2's storage identifier (`bag` for ROS 1; a directory's comes from metadata.yaml)
    suffix: str  # of a file of this format ("" for a rosbag2 directory)
    magic: bytes  # how a file of this format starts (b"" for a directory)
    reader: Callable[[Path], Any]  # rosbags' reader of such a file (or directory); not opened yet
    info: Callable[[BagInput, bool], BagInfo]  # facts from the index or summary; the flag: --freq
    rebuild: Rebuild | None = None  # `bag reindex` of one such file into a new one

    @property
    def ros_version(self) -> int:
        return 1 if self.kind == "bag" else 2
