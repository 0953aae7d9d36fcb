"""The format table: every bag format rostool reads and writes, with the functions that serve it.

What is chosen by format (how a file is recognized, what `bag info` calls it, which module gives its
facts, which rebuilds it for `bag reindex`, which rosbags reader opens a bare storage file) is looked up
here, as rosbags looks up its storage plugins; the format modules below (`ros1_info`, `mcap_info`, ...)
know only their own format and the models of `model.py`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rostool.bag.db3_info import db3_info
from rostool.bag.mcap_info import mcap_info
from rostool.bag.mcap_reindex import MAGIC as MCAP_MAGIC
from rostool.bag.mcap_reindex import rebuild_mcap
from rostool.bag.model import BagFormat, BagKind
from rostool.bag.ros1_format import MAGIC as ROS1_MAGIC
from rostool.bag.ros1_info import ros1_info
from rostool.bag.ros1_reindex import rebuild_ros1
from rostool.bag.rosbag2_metadata import rosbag2_info
from rostool.errors import RostoolError

SQLITE_MAGIC = b"SQLite format 3\x00"


def _ros1_reader(path: Path) -> Any:
    from rosbags.rosbag1 import Reader

    return Reader(path)


def _rosbag2_reader(path: Path) -> Any:
    from rosbags.rosbag2.reader import DirectoryReader

    return DirectoryReader(path)


def _mcap_reader(path: Path) -> Any:
    from rosbags.rosbag2.storage_mcap import McapReader

    return McapReader(path)


def _sqlite3_reader(path: Path) -> Any:
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

    return Sqlite3Reader(path)


FORMATS: dict[BagKind, BagFormat] = {
    fmt.kind: fmt
    for fmt in (
        BagFormat("bag", "ROS 1 bag", "bag", ".bag", ROS1_MAGIC, _ros1_reader, ros1_info, rebuild_ros1),
        BagFormat("rosbag2", "rosbag2 directory", "", "", b"", _rosbag2_reader, rosbag2_info),
        BagFormat("mcap", "mcap file", "mcap", ".mcap", MCAP_MAGIC, _mcap_reader, mcap_info, rebuild_mcap),
        BagFormat("db3", "db3 file", "sqlite3", ".db3", SQLITE_MAGIC, _sqlite3_reader, db3_info),
    )
}
FILES = tuple(fmt for fmt in FORMATS.values() if fmt.suffix)  # the formats of a single file
FILE_SUFFIXES = tuple(fmt.suffix for fmt in FILES)  # how the name of a bag file ends
STORAGES = (FORMATS["mcap"], FORMATS["db3"])  # what a rosbag2 directory's files may be
ROS1_PREFIX = b"#ROSBAG V"  # any version: a version other than 2.0 is named in its error
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"  # a file-compressed rosbag2 storage file
HEAD_SIZE = 16  # bytes that tell every format apart


def by_suffix(suffix: str) -> BagFormat | None:
    """The format a file name's suffix says (case as given: `.MCAP` is no .mcap)."""
    return next((fmt for fmt in FILES if fmt.suffix == suffix), None)


def storage_kind(path: Path) -> BagKind | None:
    """The format of a rosbag2 storage file as its name says (`.mcap`, `.db3`); None for any other."""
    return next((fmt.kind for fmt in STORAGES if fmt.suffix == path.suffix), None)


def by_storage(storage: str) -> BagFormat:
    """The bare-file format of a rosbag2 storage identifier (`mcap`, `sqlite3`)."""
    for fmt in STORAGES:
        if fmt.storage == storage:
            return fmt
    raise RostoolError(f"unknown rosbag2 storage {storage!r} (supported: mcap, sqlite3)")


def sniff(path: Path) -> BagKind | None:
    """The format of one file from its first bytes; None when it is not a bag file."""
    with path.open("rb") as handle:
        return kind_of(handle.read(HEAD_SIZE))


def kind_of(head: bytes) -> BagKind | None:
    """The format whose files start with `head` (a ROS 1 bag of any version); None for no bag file."""
    if head.startswith(ROS1_PREFIX):
        return "bag"
    return next((fmt.kind for fmt in STORAGES if head.startswith(fmt.magic)), None)
