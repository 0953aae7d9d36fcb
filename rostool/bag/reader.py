"""One reader over ROS 1 bags, rosbag2 directories and bare .mcap/.db3 files (several at once).

Built on rosbags' per-format readers. Written here because rosbags' AnyReader lacks it:
- it picks the format from the file suffix (we sniff the content, see `open.py`);
- for rosbag2 directories it matches storage channels to metadata topics by QoS too, and silently yields
  nothing when metadata.yaml and the storage disagree on QoS (e.g. the `talker_mcap` test bag); we match
  by topic and type;
- it reads a single rosbag2 bag at a time, and all-or-nothing type definitions (see `typestores.py`).
"""

from __future__ import annotations

import heapq
import struct
from collections.abc import Callable, Collection, Iterator, Sequence
from contextlib import AbstractContextManager, ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rosbags.interfaces import Connection, ConnectionExtRosbag1, MessageDefinitionFormat

from rostool.bag.failures import guard, warn
from rostool.bag.formats import FORMATS, by_storage, sniff
from rostool.bag.model import BagFormat, BagInput
from rostool.bag.open import detect, fallback_warning
from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO, StoredDefinition, TypeResolver

MessageTuple = tuple[Connection, int, bytes | memoryview]
# (connections, start ns, stop ns exclusive) -> their messages in time order
Messages = Callable[[Sequence[Connection], int | None, int | None], Iterator[MessageTuple]]

_ENCODINGS = {"ros2msg": "msg", "ros2idl": "idl", "msg": "msg", "idl": "idl"}


@dataclass
class Topic:
    """All connections of one topic across the opened bags."""

    name: str
    msgtype: str  # rosbags' normalized name, `pkg/msg/Name`
    count: int = 0
    connections: list[Connection] = field(default_factory=list)


@dataclass
class _Part:
    """One underlying rosbags reader and how its connections map to ours."""

    path: Path
    reader: Any
    messages: Messages
    connections: list[Connection]
    to_ours: dict[int, Connection] = field(default_factory=dict)
    start_ns: int = 2**63 - 1
    end_ns: int = 0


class BagReader(AbstractContextManager["BagReader"]):
    """Opens bags given as paths (or detected inputs); all must be ROS 1 or all ROS 2."""

    def __init__(self, paths: Sequence[str | Path | BagInput | Any], distro: str = DEFAULT_DISTRO) -> None:
        if not paths:
            raise RostoolError("no bag given")
        self._stack = ExitStack()
        try:
            self.inputs = [p if isinstance(p, BagInput) else detect(self._local(p)) for p in paths]
        except BaseException:
            self._stack.close()
            raise
        versions = {bag.ros_version for bag in self.inputs}
        if len(versions) > 1:
            self._stack.close()
            raise RostoolError("cannot read ROS 1 and ROS 2 bags together: convert one side first")
        self.ros_version = versions.pop()
        self.distro = distro
        self._parts: list[_Part] = []
        self.connections: list[Connection] = []
        self.topics: dict[str, Topic] = {}
        self._origin: dict[int, Path] = {}  # id(our connection) -> the file it was first seen in
        self.message_compressed = False  # a rosbag2 bag compressed message by message
        try:
            for bag in self.inputs:
                self._open(bag)
            with guard(self.paths[0] if len(self.paths) == 1 else Path(", ".join(map(str, self.paths)))):
                self.resolver = TypeResolver(
                    (conn.msgtype for conn in self.connections),
                    self._stored_definitions(),
                    self.ros_version,
                    distro,
                )
        except BaseException:
            self._stack.close()
            raise

    # -- opening ---------------------------------------------------------------------------------
    def _local(self, given: Any) -> Any:
        """A bag in object storage (s3://..., a remote.RemotePath) as a local copy kept while open."""
        from rostool.bag import remote

        if not remote.is_remote(given):
            return given
        return self._stack.enter_context(remote.local_copy(remote.resolve(given)))

    def _open(self, bag: BagInput) -> None:
        fmt = FORMATS[bag.kind]
        if bag.kind == "rosbag2":
            self._open_directory(bag, fmt.reader(bag.path))
        elif fmt.ros_version == 1:
            self._add_part(bag.path, fmt.reader(bag.path))
        else:
            self._open_storages(fmt, bag.files)

    def _open_directory(self, bag: BagInput, directory: Any) -> None:
        try:
            self._enter(bag.path, directory)
        except RostoolError as err:
            self._open_beside(bag, err)
            return
        compressed = directory.metadata.compression_mode == "message"
        self.message_compressed = self.message_compressed or compressed
        for storage, path in zip(directory.storages, bag.files, strict=False):
            self._add_storage(path, storage, compressed, counts=False)
        # Counts (and topics that no storage has) come from metadata.yaml.
        self._register(bag.path, directory.connections, counts=True)

    def _open_storages(self, fmt: BagFormat, files: Sequence[Path]) -> None:
        for path in files:
            storage = fmt.reader(path)
            self._enter(path, storage)
            self._add_storage(path, storage, False, counts=True)

    def _open_beside(self, bag: BagInput, failure: RostoolError) -> None:
        """rosbags refused the directory although metadata.yaml passed our checks: when its storage files
        open on their own, metadata.yaml was the problem; read them without it (one warning line)."""
        fmt = by_storage(bag.storage)
        if bag.metadata is None or any(sniff(path) != fmt.kind for path in bag.files):
            raise failure
        self._open_storages(fmt, bag.files)  # when they fail too, their own error names the file
        problem = str(failure).removeprefix(f"{bag.path}: ").removeprefix("cannot read bag: ")
        warn(fallback_warning(bag.metadata, f"rejected by the rosbag2 reader: {problem}", bag.files))

    def _enter(self, path: Path, reader: Any) -> None:
        with guard(path):
            reader.open()
        self._stack.callback(reader.close)

    def _add_part(self, path: Path, reader: Any) -> None:
        """A ROS 1 bag: its own reader, read through `_ros1_fast`."""
        self._enter(path, reader)
        self._add(path, reader, _ros1_messages(reader), True, reader.start_time, reader.end_time)

    def _add_storage(self, path: Path, storage: Any, compressed: bool, counts: bool) -> None:
        messages = _storage_messages(storage, compressed)
        self._add(path, storage, messages, counts, storage.metadata.start_time, storage.metadata.end_time)

    def _add(
        self, path: Path, reader: Any, messages: Messages, counts: bool, start_ns: int, end_ns: int
    ) -> None:
        conns = list(reader.connections)
        self._register(path, conns, counts)
        part = _Part(path, reader, messages, conns, start_ns=start_ns, end_ns=end_ns)
        part.to_ours = {id(c): self._ours(c) for c in conns}
        self._parts.append(part)

    def _key(self, conn: Connection) -> tuple[object, ...]:
        if isinstance(conn.ext, ConnectionExtRosbag1):
            return (conn.topic, conn.msgtype, conn.digest, conn.ext.callerid, conn.ext.latching)
        return (conn.topic, conn.msgtype)

    def _ours(self, conn: Connection) -> Connection:
        key = self._key(conn)
        return next(ours for ours in self.connections if self._key(ours) == key)

    def _register(self, path: Path, conns: Sequence[Connection], counts: bool) -> None:
        for conn in conns:
            if not isinstance(conn.topic, str) or not isinstance(conn.msgtype, str) or not conn.msgtype:
                raise RostoolError(f"{path}: cannot read bag: damaged file: a topic without name or type")
            key = self._key(conn)
            existing = next((c for c in self.connections if self._key(c) == key), None)
            topic = self.topics.get(conn.topic)
            if topic is None:  # a topic may have connections of several types; the first one names it
                topic = self.topics[conn.topic] = Topic(conn.topic, conn.msgtype)
            if existing is None:
                # The first file's own connection objects are ours: a single file needs no remapping.
                self.connections.append(conn)
                self._origin[id(conn)] = path
                topic.connections.append(conn)
            if counts:
                topic.count += conn.msgcount

    def _stored_definitions(self) -> dict[str, StoredDefinition]:
        stored: dict[str, StoredDefinition] = {}
        for part in self._parts:
            for name, encoding, text in _raw_definitions(part.reader):
                if name not in stored and encoding in _ENCODINGS:
                    stored[name] = StoredDefinition(name, _ENCODINGS[encoding], text)
            for conn in part.connections:
                fmt = conn.msgdef.format
                if fmt != MessageDefinitionFormat.NONE and conn.msgtype not in stored:
                    encoding = "idl" if fmt == MessageDefinitionFormat.IDL else "msg"
                    stored[conn.msgtype] = StoredDefinition(conn.msgtype, encoding, conn.msgdef.data)
        return stored

    # -- facts -----------------------------------------------------------------------------------
    @property
    def paths(self) -> list[Path]:
        return [bag.path for bag in self.inputs]

    @property
    def start_ns(self) -> int:
        starts = [p.start_ns for p in self._parts if p.end_ns]
        return min(starts) if starts else 0

    @property
    def end_ns(self) -> int:
        """Timestamp of the last message (inclusive)."""
        ends = [p.end_ns - 1 for p in self._parts if p.end_ns]
        return max(ends) if ends else 0

    @property
    def message_count(self) -> int:
        return sum(topic.count for topic in self.topics.values())

    # -- reading ---------------------------------------------------------------------------------
    def select(self, topics: Collection[str] = (), exclude: Collection[str] = ()) -> list[Connection]:
        """Connections of the named topics (all when none named), minus excluded ones."""
        unknown = [name for name in topics if name not in self.topics]
        if unknown:
            have = ", ".join(sorted(self.topics)) or "none"
            raise RostoolError(f"topic {unknown[0]} is not in the bag (topics: {have})")
        chosen = [c for c in self.connections if (not topics or c.topic in topics) and c.topic not in exclude]
        return chosen

    def messages(
        self,
        connections: Collection[Connection] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[MessageTuple]:
        """(our connection, timestamp ns, raw bytes) in time order; `end_ns` is inclusive."""
        wanted = {id(c) for c in (self.connections if connections is None else connections)}
        stop = None if end_ns is None else end_ns + 1
        streams = []
        for part in self._parts:
            theirs = [c for c in part.connections if id(part.to_ours[id(c)]) in wanted]
            if not theirs:
                continue
            stream = part.messages(theirs, start_ns, stop)
            identity = all(part.to_ours[id(c)] is c for c in theirs)
            streams.append(_delegated(part.path, stream) if identity else _mapped(part, stream))
        if len(streams) == 1:
            return streams[0]
        return heapq.merge(*streams, key=lambda item: item[1])

    def deserialize(self, raw: bytes | memoryview, conn: Connection) -> object:
        try:
            return self.resolver.deserialize(raw, conn.msgtype)
        except RostoolError as err:
            where = self._origin.get(id(conn), self.paths[0])
            raise RostoolError(f"{where}: {err}", err.exit_code) from err

    def close(self) -> None:
        self._stack.close()

    def __exit__(self, *_exc: object) -> None:
        self.close()


def _delegated(path: Path, stream: Iterator[MessageTuple]) -> Iterator[MessageTuple]:
    with guard(path):
        yield from stream


def _mapped(part: _Part, stream: Iterator[MessageTuple]) -> Iterator[MessageTuple]:
    to_ours = part.to_ours
    with guard(part.path):
        for conn, timestamp, data in stream:
            yield to_ours[id(conn)], timestamp, data


def _ros1_messages(reader: Any) -> Messages:
    def messages(conns: Sequence[Connection], start: int | None, stop: int | None) -> Iterator[Any]:
        return _ros1_fast(reader, conns, start, stop)

    return messages


_U32 = struct.Struct("<I")
_MSG_OP = b"op=\x02"


def _ros1_fast(
    reader: Any, conns: Sequence[Connection], start: int | None, stop: int | None
) -> Iterator[Any]:
    """rosbags' rosbag1 Reader.messages, about twice as fast: it merges IndexData entries with Python-level
    comparisons and parses every record header into a dict; here the index it already read is sorted once
    as plain tuples and each record's data is located with struct. Anything unexpected (e.g. an index
    entry pointing at a connection record) is left to rosbags' own code."""
    by_id = {conn.id: conn for conn in conns}
    entries = sorted(
        (entry.time, entry.chunk_pos, entry.offset, conn_id)
        for conn_id in by_id
        for entry in reader.indexes.get(conn_id, ())
        if (start is None or entry.time >= start) and (stop is None or entry.time < stop)
    )
    chunks = reader.chunks
    bio = reader.bio
    current = -1
    data = b""
    recent: dict[int, bytes] = {}  # a few decompressed chunks, for chunks that overlap in time
    unpack = _U32.unpack_from
    for timestamp, chunk_pos, offset, conn_id in entries:
        if chunk_pos != current:
            cached = recent.get(chunk_pos)
            if cached is None:
                chunk = chunks[chunk_pos]
                bio.seek(chunk.datapos)
                raw = bio.read(chunk.datasize)
                if len(raw) != chunk.datasize:
                    raise EOFError(f"chunk at {chunk_pos} is cut short")
                cached = recent[chunk_pos] = chunk.decompressor(raw)
                if len(recent) > 4:
                    del recent[next(iter(recent))]
            data = cached
            current = chunk_pos
        (header_len,) = unpack(data, offset)
        body = offset + 4 + header_len
        if data.find(_MSG_OP, offset + 4, body) < 0:
            yield from reader.messages(connections=[by_id[conn_id]], start=timestamp, stop=timestamp + 1)
            continue
        (size,) = unpack(data, body)
        yield by_id[conn_id], timestamp, data[body + 4 : body + 4 + size]


def _storage_messages(storage: Any, compressed: bool) -> Messages:
    if not compressed:

        def plain(conns: Sequence[Connection], start: int | None, stop: int | None) -> Iterator[Any]:
            return storage.messages(conns, start, stop)  # type: ignore[no-any-return]

        return plain

    from rosbags.rosbag2.reader import zstd

    def decompressed(conns: Sequence[Connection], start: int | None, stop: int | None) -> Iterator[Any]:
        for conn, timestamp, data in storage.messages(conns, start, stop):
            yield conn, timestamp, zstd.decompress(data)

    return decompressed


def _raw_definitions(reader: Any) -> Iterator[tuple[str, str, str]]:
    """Every definition a storage holds, also those no topic uses by that name (service types)."""
    for schema in getattr(reader, "schemas", {}).values():  # McapReader
        yield schema.name, schema.encoding, schema.data
    for entry in getattr(reader, "msgtypes", []):  # Sqlite3Reader
        yield entry["name"], entry["encoding"], entry["msgdef"]
