"""`ros2 bag record --storage-config-file FILE` (and `--storage-preset-profile NAME`, rosbag2's presets of
the same options, which the file's options override): the storage plugin's own YAML options, as rosbag2
reads them.

- mcap: rosbag2_storage_mcap's keys (mcap::McapWriterOptions): chunkSize, compression (None, Lz4, Zstd),
  compressionLevel, noChunking, noMessageIndex, noSummary, noCRC / noChunkCRC / noAttachmentCRC /
  noSummaryCRC, enableDataCRC, forceCompression, noRepeatedSchemas, noRepeatedChannels,
  noAttachmentIndex, noMetadataIndex, noChunkIndex, noStatistics, noSummaryOffsets. The file is then
  written by the mcap library's writer (`ConfiguredMcapWriter`, in place of rosbags' own); keys the file
  leaves out keep McapWriterOptions' defaults (Zstd, 768 KiB chunks). Chunks are compressed at the
  library's level whatever compressionLevel says, and always (forceCompression).
- sqlite3: rosbag2_storage_default_plugins' `write: {pragmas: ["journal_mode = MEMORY", ...]}` (and `read`,
  for playing, accepted): each pragma runs on the new database before its tables are created.
An unknown key or a bad value is one line naming it.
"""

from __future__ import annotations

import copy
import re
import sqlite3
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from rosbags.rosbag2.enums import CompressionMode
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer

from rostool.errors import RostoolError

_BOOLS = (
    "noCRC", "noChunkCRC", "noAttachmentCRC", "noSummaryCRC", "enableDataCRC", "noChunking", "noMessageIndex",
    "noSummary", "forceCompression", "noRepeatedSchemas", "noRepeatedChannels", "noAttachmentIndex",
    "noMetadataIndex", "noChunkIndex", "noStatistics", "noSummaryOffsets",
)  # fmt: skip
_COMPRESSIONS = ("None", "Lz4", "Zstd")
_LEVELS = ("Fastest", "Fast", "Default", "Slow", "Slowest")
_PRAGMA = re.compile(r"\s*[A-Za-z_]\w*\s*(=\s*[\w.+-]+|\(\s*[\w.+-]+\s*\))?\s*")
DEFAULT_CHUNK_SIZE = 768 * 1024  # mcap::McapWriterOptions' default
# rosbag2's --storage-preset-profile values, as its storage plugins define them
PRESETS: dict[str, dict[str, dict[str, Any]]] = {
    "mcap": {
        "fastwrite": {"noChunking": True, "noCRC": True},
        "zstd_fast": {"compression": "Zstd", "compressionLevel": "Fastest", "noCRC": True},
        "zstd_small": {"compression": "Zstd", "compressionLevel": "Slowest", "chunkSize": 4 * 1024 * 1024},
    },
    "sqlite3": {"resilient": {"write": {"pragmas": ["journal_mode = WAL", "synchronous = NORMAL"]}}},
}


@dataclass(frozen=True)
class StorageConfig:
    """What a storage config file asks of the writer of one storage (`mcap` or `sqlite3`)."""

    storage: str
    source: str  # the file, for messages
    mcap: dict[str, Any] = field(default_factory=dict)  # the mcap library Writer's arguments
    pragmas: tuple[str, ...] = ()  # sqlite3, run in order on the new database

    def writer_factory(self) -> Any:
        """The rosbags storage writer class to use in place of the plugin's own (called as it is)."""
        if self.storage == "mcap":
            return partial(ConfiguredMcapWriter, options=self.mcap)
        return partial(PragmaSqlite3Writer, pragmas=self.pragmas, source=self.source)


def load_storage_config(path: str | None, storage: str, preset: str | None = None) -> StorageConfig:
    """The options of `--storage-preset-profile` (rosbag2's presets), then the config file's over them."""
    document: dict[Any, Any] = {}
    source = f"--storage-config-file {path}"
    if preset is not None:
        source = f"--storage-preset-profile {preset}"
        known = PRESETS[storage]
        if preset not in known:
            raise _bad(source, f"unknown for {storage} storage (known: {', '.join(sorted(known))})")
        document = copy.deepcopy(known[preset])
    if path is not None:
        source = f"--storage-config-file {path}"
        given = _read(path, source)
        if storage == "sqlite3" and "write" in document and isinstance(given.get("write"), dict):
            pragmas = [*document["write"]["pragmas"], *(given["write"].get("pragmas") or [])]
            given["write"] = {**given["write"], "pragmas": pragmas}
        document = {**document, **given}
    if storage == "mcap":
        return StorageConfig(storage, source, mcap=_mcap_options(document, source))
    return StorageConfig(storage, source, pragmas=_pragmas(document, source))


def _read(path: str, source: str) -> dict[Any, Any]:
    import yaml

    try:
        document = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except OSError as err:
        raise _bad(source, err.strerror or str(err)) from err
    except yaml.YAMLError as err:
        raise _bad(source, f"not YAML: {' '.join(str(err).split())}") from err
    document = {} if document is None else document
    if not isinstance(document, dict):
        raise _bad(source, "expected a mapping of options")
    return document


def _bad(source: str, text: str) -> RostoolError:
    return RostoolError(f"{source}: {text}")


def _mcap_options(document: dict[Any, Any], path: str) -> dict[str, Any]:
    from mcap.writer import CompressionType, IndexType

    known = {*_BOOLS, "chunkSize", "compression", "compressionLevel"}
    unknown = sorted(str(key) for key in document if key not in known)
    if unknown:
        raise _bad(path, f"unknown mcap option {unknown[0]} (known: {', '.join(sorted(known))})")
    for key in _BOOLS:
        if key in document and not isinstance(document[key], bool):
            raise _bad(path, f"{key} must be true or false, not {document[key]!r}")
    flag = {key: bool(document.get(key, False)) for key in _BOOLS}
    chunk_size = document.get("chunkSize", DEFAULT_CHUNK_SIZE)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size <= 0:
        raise _bad(path, f"chunkSize must be a positive number of bytes, not {chunk_size!r}")
    compression = document.get("compression", "Zstd")
    if compression not in _COMPRESSIONS:
        raise _bad(path, f"compression must be one of {', '.join(_COMPRESSIONS)}, not {compression!r}")
    level = document.get("compressionLevel", "Default")
    if level not in _LEVELS:
        raise _bad(path, f"compressionLevel must be one of {', '.join(_LEVELS)}, not {level!r}")
    index = IndexType.ALL
    kinds = {"noMessageIndex": IndexType.MESSAGE, "noChunkIndex": IndexType.CHUNK,
             "noAttachmentIndex": IndexType.ATTACHMENT, "noMetadataIndex": IndexType.METADATA}  # fmt: skip
    for key, kind in kinds.items():
        if flag[key] or flag["noSummary"]:
            index &= ~kind
    no_crc = flag["noCRC"] or flag["noChunkCRC"]
    return {
        "chunk_size": chunk_size,
        "compression": CompressionType[compression.upper()],
        "index_types": index,
        "repeat_channels": not (flag["noRepeatedChannels"] or flag["noSummary"]),
        "repeat_schemas": not (flag["noRepeatedSchemas"] or flag["noSummary"]),
        "use_chunking": not flag["noChunking"],
        "use_statistics": not (flag["noStatistics"] or flag["noSummary"]),
        "use_summary_offsets": not (flag["noSummaryOffsets"] or flag["noSummary"]),
        "enable_crcs": not no_crc,
        "enable_data_crcs": flag["enableDataCRC"] and not flag["noCRC"],
    }


def _pragmas(document: dict[Any, Any], path: str) -> tuple[str, ...]:
    unknown = sorted(str(key) for key in document if key not in ("read", "write"))
    if unknown:
        raise _bad(path, f"unknown sqlite3 option {unknown[0]} (known: read, write)")
    found: dict[str, list[str]] = {}
    for side in ("read", "write"):
        section = document.get(side) or {}
        if not isinstance(section, dict) or set(section) - {"pragmas"}:
            raise _bad(path, f"{side}: expected `pragmas: [...]` only")
        pragmas = section.get("pragmas") or []
        if not isinstance(pragmas, list) or not all(isinstance(p, str) for p in pragmas):
            raise _bad(path, f"{side}.pragmas must be a list of strings such as 'journal_mode = MEMORY'")
        for pragma in pragmas:
            if not _PRAGMA.fullmatch(pragma):
                raise _bad(path, f"bad pragma {pragma!r}: expected NAME, NAME = VALUE or NAME(VALUE)")
        found[side] = pragmas
    return tuple(found["write"])


class ConfiguredMcapWriter:
    """rosbags' storage writer interface over the mcap library's Writer with the config file's options."""

    def __init__(self, path: Path, compression: Any, options: dict[str, Any]) -> None:
        from mcap.writer import Writer

        _ = compression  # rosbags' storage compression is the config file's `compression` here
        self.path = path / f"{path.name}.mcap"
        self.bio = self.path.open("xb")
        self.writer = Writer(self.bio, **options)
        self.writer.start(profile="ros2", library="rostool")
        self.schemas: dict[str, int] = {}
        self.channels: dict[int, int] = {}

    def add_msgtype(self, connection: Any) -> None:
        from rosbags.interfaces import MessageDefinitionFormat

        encoding = "ros2msg" if connection.msgdef.format == MessageDefinitionFormat.MSG else "ros2idl"
        data = connection.msgdef.data.encode()
        self.schemas[connection.msgtype] = self.writer.register_schema(connection.msgtype, encoding, data)

    def add_connection(self, connection: Any, offered_qos_profiles: str) -> None:
        self.channels[connection.id] = self.writer.register_channel(
            connection.topic, connection.ext.serialization_format, self.schemas[connection.msgtype],
            {"offered_qos_profiles": offered_qos_profiles},
        )  # fmt: skip

    def write(self, connection: Any, timestamp: int, data: bytes | memoryview) -> None:
        self.writer.add_message(self.channels[connection.id], timestamp, bytes(data), timestamp)

    def flush(self) -> None:
        """What is written so far reaches the OS; the chunk being filled stays (chunkSize is honoured)."""
        self.bio.flush()

    def close(self, version: int, metadata: str) -> None:
        _ = version
        self.writer.add_metadata("rosbag2", {"serialized_metadata": metadata})
        self.writer.finish()
        self.bio.close()

    def abort(self) -> None:
        self.bio.close()


class PragmaSqlite3Writer(Sqlite3Writer):
    """rosbags' sqlite3 storage writer, with the config file's pragmas run before its tables exist (as
    rosbag2 runs them: page_size, for one, applies only then)."""

    def __init__(self, path: Path, compression: Any, pragmas: tuple[str, ...] = (), source: str = "") -> None:
        if compression == CompressionMode.STORAGE:
            raise RostoolError("sqlite3 storage has no compression of its own")
        self.path = path / f"{path.name}.db3"
        self.conn = sqlite3.connect(f"file:{self.path}", uri=True)
        for pragma in pragmas:
            try:
                self.conn.execute(f"PRAGMA {pragma}")
            except sqlite3.Error as err:
                self.conn.close()
                raise _bad(source, f"pragma {pragma!r} failed: {err}") from err
        self.conn.executescript(self.SQLITE_SCHEMA)
        self.cursor = self.conn.cursor()
