"""The files `bag record` writes into, one `Sink` each: a ROS 1 bag (`ros1_writer.BagWriter`) or one rosbag2
storage file, .mcap or .db3 (rosbags' writer), each written under its `.active` name and moved into place when
closed. Messages arrive as the publisher sent them (ROS 1 bytes or CDR, `RecordSource.encoding`) and are
converted where the bag holds the other serialization.
"""

from __future__ import annotations

import contextlib
import shutil
import sqlite3
import time
from collections.abc import Callable, Mapping
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from rostool.bag.crossver import CrossVersionStores
from rostool.bag.model import BagFormat
from rostool.bag.replace import remove_bag, swap_into_place
from rostool.bag.ros1_writer import BagWriter, WriteFailed
from rostool.bag.rosbag2_metadata import METADATA
from rostool.errors import RostoolError
from rostool.graph.recording import RecordSource

if TYPE_CHECKING:
    from rostool.bag.storage_config import StorageConfig


def _volatile(best_effort: bool) -> Any:
    """A volatile publisher's offered QoS as rosbag2 stores it (rosbags' LATCH, but volatile): history and
    depth unknown, as rmw reports a remote publisher's."""
    from rosbags.convert.converter import LATCH
    from rosbags.interfaces import QosDurability, QosReliability

    reliability = QosReliability.BEST_EFFORT if best_effort else QosReliability.RELIABLE
    return LATCH[0]._replace(reliability=reliability, durability=QosDurability.VOLATILE)


def active_name(path: Path) -> Path:
    return path.with_name(path.name + ".active")


class Sink(Protocol):
    final: Path
    active: Path
    problems: dict[str, str]  # topic -> why some of its messages were not written

    @property
    def size(self) -> int: ...

    def write(self, key: object, header: Mapping[str, str], time_ns: int, payload: bytes) -> bool: ...

    def flush(self) -> None: ...

    def close(self) -> None: ...


def _open_failure(path: Path, err: OSError) -> RostoolError:
    reason = err.strerror or str(err)
    return RostoolError(f"{path}: cannot create the bag: {reason}")


class Ros1Sink:
    """One ROS 1 bag: ROS 1 bytes with the publisher's connection header, or ROS 2 CDR converted."""

    def __init__(self, final: Path, compression: str, force: bool, source: RecordSource) -> None:
        self.final = final
        self.active = active_name(final)
        if force:  # check_target made sure it is a bag
            remove_bag(self.active)
        try:
            self.writer = BagWriter(self.active, compression)
        except OSError as err:
            raise _open_failure(self.active, err) from err
        self.source = source
        self._stores = CrossVersionStores(1)
        self._conns: dict[object, tuple[int, Callable[[bytes], Any] | None] | None] = {}
        self.problems: dict[str, str] = {}

    @property
    def size(self) -> int:
        return self.writer.size

    def write(self, key: object, header: Mapping[str, str], time_ns: int, payload: bytes) -> bool:
        entry = self._conns.get(key, False)
        if entry is False:
            entry = self._conns[key] = self._add(header)
        if entry is None:
            return False
        conn, convert = entry
        if convert is not None:
            try:
                payload = convert(payload)
            except Exception as err:  # bytes that do not match the announced type
                self.problems.setdefault(header["topic"], f"cannot convert a {header['type']} message: {err}")
                return False
        self.writer.write(conn, time_ns, payload)
        return True

    def _add(self, header: Mapping[str, str]) -> tuple[int, Callable[[bytes], Any] | None] | None:
        if self.source.encoding == "ros1":
            return self.writer.connection(header), None
        try:
            ros1_header, convert = ros1_header_for_cdr(dict(header), self.source.store, self._stores)
        except Exception as err:  # a type rosbags cannot express in ROS 1
            self.problems[header["topic"]] = f"cannot write {header['type']} to a ROS 1 bag: {err}"
            return None
        return self.writer.connection(ros1_header), convert

    def flush(self) -> None:
        self.writer.flush()

    def close(self) -> None:
        writer = self.writer
        try:
            writer.close()
        except WriteFailed as err:
            raise RostoolError(
                f"{self.active}: cannot finish the bag ({err}); everything written is in it: free some "
                f"space, then run `rostool bag reindex {self.active}`"
            ) from err
        swap_into_place(self.active, self.final)
        failed = writer.failed
        if failed is not None:
            raise RostoolError(
                f"{self.final}: {failed.strerror or failed}: the bag holds the {writer.kept} of "
                f"{writer.messages} messages that reached the disk"
            )


class Ros2Sink:
    """One .mcap or .db3 file (rosbags' writer): ROS 2 CDR as received, or ROS 1 messages converted to CDR
    with ROS 2 type names."""

    def __init__(
        self,
        final: Path,
        fmt: BagFormat,
        source: RecordSource,
        force: bool,
        compression: tuple[str, str] | None = None,
        storage_config: StorageConfig | None = None,
    ) -> None:
        from rosbags.rosbag2 import StoragePlugin
        from rosbags.rosbag2 import Writer as Writer2

        self.final = final
        self.active = active_name(final)
        self.fmt = fmt
        self.source = source
        self._stores = CrossVersionStores(2)
        if force:  # check_target made sure it is a bag
            remove_bag(self.active)
        plugin = StoragePlugin[fmt.storage.upper()]
        try:
            self.writer: Any = Writer2(self.active, version=9, storage_plugin=plugin)
            if storage_config is not None:  # --storage-config-file: the storage's writer with its options
                plugins = {**Writer2.STORAGE_PLUGINS, plugin: storage_config.writer_factory()}
                self.writer.STORAGE_PLUGINS = plugins
            if compression is not None:
                from rosbags.rosbag2.enums import CompressionFormat, CompressionMode

                mode, form = compression  # rosbag2's --compression-mode file|message, --compression-format
                self.writer.set_compression(CompressionMode[mode.upper()], CompressionFormat[form.upper()])
            self.writer.open()
        except OSError as err:
            raise _open_failure(self.active, err) from err
        except Exception as err:  # rosbags' WriterError
            raise RostoolError(f"{self.active}: cannot create the bag: {err}") from err
        self._conns: dict[object, tuple[Any, Callable[[bytes], Any]] | None] = {}
        self._shared: dict[tuple[str | None, str | None, str | None, bool], tuple[Any, Any]] = {}
        self.problems: dict[str, str] = {}
        self._bytes = 0
        self._chunk_started: float | None = None  # when the pending mcap chunk got its first message
        self.metadata: dict[str, Any] = {}  # the part's rosbag2 metadata, read when closed
        self.compressed = compression is not None
        self.configured = storage_config is not None

    @property
    def size(self) -> int:
        return self._bytes

    def write(self, key: object, header: Mapping[str, str], time_ns: int, payload: bytes) -> bool:
        if key not in self._conns:
            self._conns[key] = self._add(header)
        entry = self._conns[key]
        if entry is None:
            return False
        conn, convert = entry
        try:
            data = convert(payload)
        except Exception as err:  # bytes that do not match the publisher's own definition
            self.problems.setdefault(header["topic"], f"cannot convert a {header['type']} message: {err}")
            return False
        self.writer.write(conn, time_ns, data)
        self._bytes += len(data)
        if self._chunk_started is None:
            self._chunk_started = time.monotonic()
        return True

    def _add(self, header: Mapping[str, str]) -> tuple[Any, Callable[[bytes], Any]] | None:
        # Several publishers of one topic (/tf, /rosout) share its one connection: rosbags takes a
        # (topic, type, QoS) once.
        same = (header.get("topic"), header.get("type"), header.get("md5sum"), header.get("latching") == "1",
                header.get("reliability"))  # fmt: skip
        if same in self._shared:
            return self._shared[same]
        entry = self._add_connection(header)
        if entry is not None:
            self._shared[same] = entry
        return entry

    def _add_connection(self, header: Mapping[str, str]) -> tuple[Any, Callable[[bytes], Any]] | None:
        from functools import partial

        from rosbags.convert.converter import LATCH, STATIC_MSGTYPE_RENAMES

        qos = list(LATCH) if header.get("latching") == "1" else []
        try:
            if self.source.encoding == "cdr":
                qos = qos or [_volatile(header.get("reliability") == "best_effort")]
                conn = self.writer.add_connection(
                    header["topic"], header["type"], typestore=self.source.store, offered_qos_profiles=qos
                )
                return conn, _unchanged
            msg_type = self.source.types.resolve(
                header.get("type", ""), header.get("md5sum", "*"), header.get("message_definition")
            )
            msgtype = STATIC_MSGTYPE_RENAMES.get(msg_type.store_name, msg_type.store_name)
            store = self._stores.store_for(msg_type.store, msg_type.store_name, msgtype)
            conn = self.writer.add_connection(
                header["topic"], msgtype, typestore=store, offered_qos_profiles=qos
            )
        except Exception as err:  # a type rosbags cannot express in ROS 2
            self.problems[header["topic"]] = f"cannot write {header.get('type')} to a ROS 2 bag: {err}"
            return None
        return conn, partial(store.ros1_to_cdr, typename=msgtype)

    def flush(self) -> None:
        storage = self.writer.storage
        if storage is None:
            return
        if self.compressed:  # the file is written through a compressor: nothing to push early
            return
        if self.fmt.kind == "mcap" and self.configured:
            storage.flush()  # chunks as the config file sizes them
        elif self.fmt.kind == "mcap":
            # Close the pending chunk once its oldest message is 1 s old, so a killed recorder loses at
            # most that second (counted from the last close instead, a chunk begun late in a quiet
            # second was held until the next one).
            started = self._chunk_started
            if storage.chunk.bio.tell() and started is not None and time.monotonic() - started >= 1.0:
                storage.close_chunk()
                self._chunk_started = None
            storage.bio.flush()
        else:
            storage.conn.commit()

    def close(self) -> None:
        from rosbags.rosbag2 import WriterError

        try:
            self.writer.close()
        except (OSError, sqlite3.Error, WriterError) as err:  # e.g. disk full
            reason = err.strerror if isinstance(err, OSError) and err.strerror else str(err)
            raise RostoolError(
                f"{self.active}: cannot finish the bag: {reason}; what was written is in "
                f"{self.active}: free some space, then run `rostool bag reindex {self.active}`"
            ) from err
        import yaml

        with contextlib.suppress(OSError, yaml.YAMLError, TypeError):
            text = (self.active / METADATA).read_text()
            self.metadata = yaml.safe_load(text)["rosbag2_bagfile_information"]
        produced = self.active / f"{self.active.name}{self.fmt.suffix}"
        if not produced.exists():  # file compression: NAME.mcap.zstd
            produced = next(self.active.glob(f"{self.active.name}{self.fmt.suffix}.*"), produced)
            self.final = self.final.with_name(
                self.final.name + produced.name[len(self.active.name) + len(self.fmt.suffix) :]
            )
        swap_into_place(produced, self.final)
        shutil.rmtree(self.active, ignore_errors=True)


def _unchanged(payload: bytes) -> bytes:
    return payload


def ros1_header_for_cdr(
    fields: dict[str, str], src_store: Any, stores: CrossVersionStores
) -> tuple[dict[str, str], Callable[[bytes], Any]]:
    """A ROS 1 connection header (type, md5sum, definition) and byte converter for a ROS 2 type."""
    msgtype = fields["type"]
    if "/msg/" not in msgtype:
        raise RostoolError(f"type {msgtype} has no ROS 1 equivalent")
    dst = stores.store_for(src_store, msgtype, msgtype)
    text, md5 = dst.generate_msgdef(msgtype, ros_version=1)
    header = {
        "topic": fields["topic"],
        "type": msgtype.replace("/msg/", "/"),
        "md5sum": md5,
        "message_definition": text,
        "callerid": fields["callerid"],
        "latching": fields["latching"],
    }
    return header, partial(src_store.cdr_to_ros1, typename=msgtype)
