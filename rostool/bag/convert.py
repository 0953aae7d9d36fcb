"""`bag convert` and `bag filter`: copy selected messages from bags into a new bag of any format.

Writing is rosbags' (rosbag1.Writer, rosbag2.Writer) and so is the ROS 1 <-> CDR byte conversion
(`ros1_to_cdr` / `cdr_to_ros1`, the tf/tfMessage rename and latching QoS of rosbags.convert). Written
here because rosbags.convert lacks it: reading through our BagReader (sniffed inputs, per-type
definitions, several ROS 2 bags), single-file .mcap/.db3 outputs, an atomic temporary output,
message predicates, and errors as one line instead of prints on stdout.

Outputs: `X.bag` -> ROS 1 bag; `X.mcap` / `X.db3` -> one self-describing storage file (rosbag2
storage with definitions and type hashes, readable by rosbags' AnyReader and `ros2 bag`, no
metadata.yaml); any other name -> a rosbag2 directory (metadata.yaml version 8, mcap unless --format db3).
"""

from __future__ import annotations

import os
import shutil
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from rosbags.interfaces import Connection, ConnectionExtRosbag1, ConnectionExtRosbag2
from rosbags.typesys.store import Typestore

from rostool.bag.crossver import CrossVersionStores
from rostool.bag.failures import describe
from rostool.bag.formats import FORMATS, by_storage, by_suffix
from rostool.bag.model import BagFormat, BagInput
from rostool.bag.open import detect
from rostool.bag.reader import BagReader
from rostool.bag.replace import check_replaceable, swap_into_place
from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO

OutputFormat = Literal["bag", "mcap", "db3"]
Predicate = Callable[[object, str, int], bool]  # (message, topic, timestamp ns) -> keep
ROSBAG2_VERSION: Literal[8] = 8  # readable by jazzy and newer (kilted writes 9)


@dataclass(frozen=True)
class Output:
    path: Path
    layout: Literal["bag", "file", "dir"]
    fmt: BagFormat  # a ROS 1 bag, or the storage of the ROS 2 file or directory

    @property
    def ros_version(self) -> int:
        return self.fmt.ros_version


@dataclass
class Selection:
    topics: Sequence[str] = ()
    exclude: Sequence[str] = ()
    start: str | None = None  # seconds since epoch, or `+S` seconds after the bag's start
    end: str | None = None
    predicate: Predicate | None = None


@dataclass
class Result:
    output: Output
    written: int = 0
    read: int = 0
    topics: dict[str, int] = field(default_factory=dict)


def plan_output(dst: str | Path, fmt: OutputFormat | None, like: BagInput | None = None) -> Output:
    """Where and how to write: from DST's suffix, `--format`, else like the input (filter) or mcap dir."""
    path = Path(dst)
    named = by_suffix(path.suffix.lower())
    if fmt is not None and named is not None and named.kind != fmt:
        raise RostoolError(f"{path}: the name says {named.kind} but --format says {fmt}")
    chosen = FORMATS[fmt] if fmt is not None else named
    if chosen is not None:
        return _output(path, chosen, single_file=named is not None)
    if like is not None and like.kind == "rosbag2":
        return _output(path, by_storage(like.storage), single_file=False)
    if like is not None:
        return _output(path, FORMATS[like.kind], single_file=len(like.files) == 1)
    return _output(path, FORMATS["mcap"], single_file=False)


def _output(path: Path, fmt: BagFormat, single_file: bool) -> Output:
    """A ROS 1 bag is a file; ROS 2 storage is one file where asked, else a rosbag2 directory of it."""
    if fmt.ros_version == 1:
        return Output(path, "bag", fmt)
    return Output(path, "file" if single_file else "dir", fmt)


def parse_time(text: str | None, bag_start_ns: int, name: str) -> int | None:
    if text is None:
        return None
    value = text.strip()
    try:
        if value.startswith("+"):
            return bag_start_ns + round(float(value[1:]) * 1e9)
        return round(float(value) * 1e9)
    except ValueError as err:
        raise RostoolError(
            f"--{name} {text!r}: expected seconds since epoch, or +S after the bag start"
        ) from err


def copy_bags(
    sources: Sequence[str | Path],
    dst: str | Path,
    fmt: OutputFormat | None = None,
    selection: Selection | None = None,
    distro: str = DEFAULT_DISTRO,
    force: bool = False,
    progress: bool | None = None,
    like_input: bool = False,
) -> Result:
    """Copy (and convert) the selected messages of `sources` into `dst`."""
    selection = selection or Selection()
    inputs = [detect(src) for src in sources]
    output = plan_output(dst, fmt, inputs[0] if like_input else None)
    _check_destination(output.path, inputs, force)
    with BagReader(inputs, distro) as reader:
        conns = reader.select(selection.topics, selection.exclude)
        start = parse_time(selection.start, reader.start_ns, "start")
        end = parse_time(selection.end, reader.start_ns, "end")
        total = sum(c.msgcount for c in conns)
        with _atomic(output, force) as tmp_path:
            sink = _Sink(output, tmp_path, reader)
            result = Result(output)
            try:
                stream = reader.messages(conns, start, end) if conns else iter(())
                with _progress(total, progress, output.path.name) as advance:
                    for conn, timestamp, data in stream:
                        result.read += 1
                        advance()
                        if selection.predicate is not None:
                            msg = reader.deserialize(data, conn)
                            if not selection.predicate(msg, conn.topic, timestamp):
                                continue
                        sink.write(conn, timestamp, data)
                        result.written += 1
                        result.topics[conn.topic] = result.topics.get(conn.topic, 0) + 1
                for conn in conns:  # topics without (kept) messages still belong in the output
                    sink.connection(conn)
                sink.close()
            except BaseException:
                sink.abort()
                raise
    return result


def _check_destination(path: Path, inputs: Sequence[BagInput], force: bool) -> None:
    target = path.resolve()
    for bag in inputs:
        if target == bag.path.resolve() or target in {f.resolve() for f in bag.files}:
            raise RostoolError(f"{path}: the output is also an input; choose another name")
    if (path.exists() or path.is_symlink()) and not force:
        raise RostoolError(f"{path} exists; pass --force to overwrite it")
    check_replaceable(path, [p for bag in inputs for p in (bag.path, *bag.files)])
    if not path.parent.exists():
        raise RostoolError(f"{path.parent}: no such directory")


@contextmanager
def _atomic(output: Output, force: bool) -> Iterator[Path]:
    """Write under a hidden temporary directory next to DST; move into place only on success."""
    work = output.path.parent / f".{output.path.name}.rostool-{os.getpid()}"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    try:
        inner = work / (output.path.stem if output.layout == "file" else output.path.name)
        yield inner
        produced = inner
        if output.layout == "file":
            produced = inner / f"{inner.name}{output.fmt.suffix}"
        if output.path.exists() or output.path.is_symlink():
            if not force:
                raise RostoolError(f"{output.path} appeared while converting; pass --force to overwrite it")
            check_replaceable(output.path)
        swap_into_place(produced, output.path)
    finally:
        shutil.rmtree(work, ignore_errors=True)


@contextmanager
def _progress(total: int, enabled: bool | None, label: str) -> Iterator[Callable[[], None]]:
    """A rich progress bar on stderr when it is a terminal; a no-op otherwise."""
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled or total <= 0:
        yield lambda: None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task(f"writing {label}", total=total)
        step = max(1, total // 200)
        count = 0

        def advance() -> None:
            nonlocal count
            count += 1
            if count % step == 0:
                bar.update(task, completed=count)

        yield advance


class _Sink:
    """The writer of one output plus per-connection definition and byte conversion."""

    def __init__(self, output: Output, path: Path, reader: BagReader) -> None:
        self.output = output
        self.reader = reader
        self.src_version = reader.ros_version
        self.dst_version = output.ros_version
        self.connections: dict[int, tuple[Connection, Callable[[Any], Any]]] = {}
        self._dst_stores = CrossVersionStores(self.dst_version)
        self.writer: Any
        with _writing(path):
            if output.ros_version == 1:
                from rosbags.rosbag1 import Writer as Writer1

                self.writer = Writer1(path)
            else:
                from rosbags.rosbag2 import StoragePlugin
                from rosbags.rosbag2 import Writer as Writer2

                plugin = StoragePlugin[output.fmt.storage.upper()]
                self.writer = Writer2(path, version=ROSBAG2_VERSION, storage_plugin=plugin)
            self.writer.open()

    def write(self, conn: Connection, timestamp: int, data: bytes | memoryview) -> None:
        entry = self.connections.get(id(conn))
        if entry is None:
            self.reader.resolver.validate(data, conn.msgtype)
            entry = self._add(conn)
        dst_conn, convert = entry
        try:
            payload = convert(data)
        except Exception as err:
            raise RostoolError(
                f"cannot convert a {conn.msgtype} message on {conn.topic} to ROS {self.dst_version}: "
                f"{describe(err)}"
            ) from err
        self.writer.write(dst_conn, timestamp, payload)

    def connection(self, conn: Connection) -> None:
        """Make sure `conn` exists in the output (a topic whose messages were all filtered out)."""
        if id(conn) not in self.connections:
            self._add(conn)

    def _add(self, conn: Connection) -> tuple[Connection, Callable[[Any], Any]]:
        try:
            entry = self._create(conn)
        except RostoolError:
            raise
        except Exception as err:
            raise RostoolError(
                f"cannot write type {conn.msgtype} (topic {conn.topic}) to a ROS {self.dst_version} bag: "
                f"{describe(err)}"
            ) from err
        self.connections[id(conn)] = entry
        return entry

    def _create(self, conn: Connection) -> tuple[Connection, Callable[[Any], Any]]:
        from functools import partial

        from rosbags.convert.converter import LATCH, STATIC_MSGTYPE_RENAMES

        resolver = self.reader.resolver
        if conn.msgtype in resolver.unknown and self.src_version == 2:
            # Without a definition the output would not be self-describing (nor convertible).
            raise RostoolError(resolver.missing_message(conn.msgtype))
        store = resolver.store
        writer = self.writer
        if self.src_version == self.dst_version == 1:
            assert isinstance(conn.ext, ConnectionExtRosbag1)
            dst = _find_or_add1(
                writer,
                conn.topic,
                conn.msgtype,
                msgdef=conn.msgdef.data,
                md5sum=conn.digest,
                callerid=conn.ext.callerid,
                latching=conn.ext.latching,
            )
            return dst, _identity
        if self.dst_version == 1 and "/msg/" not in conn.msgtype:
            raise RostoolError(
                f"type {conn.msgtype} (topic {conn.topic}) has no ROS 1 equivalent; "
                f"leave it out with --exclude-topics {conn.topic}"
            )
        if self.src_version == self.dst_version == 2:
            assert isinstance(conn.ext, ConnectionExtRosbag2)
            qos = conn.ext.offered_qos_profiles
            if "/msg/" not in conn.msgtype:
                # rosbags cannot generate .msg text for service/action types: keep the stored .srv text,
                # as rosbag2 itself stores it.
                text = resolver.stored_text(conn.msgtype)
                digest = conn.digest or store.hash_rihs01(conn.msgtype)
                dst = _find_or_add2(writer, conn.topic, conn.msgtype, qos, msgdef=text, rihs01=digest)
            else:
                dst = _find_or_add2(writer, conn.topic, conn.msgtype, qos, typestore=store)
            return dst, _identity
        if self.src_version == 1:
            assert isinstance(conn.ext, ConnectionExtRosbag1)
            msgtype = STATIC_MSGTYPE_RENAMES.get(conn.msgtype, conn.msgtype)
            dst_store = self._dst_store(store, conn.msgtype, msgtype)
            qos = LATCH if conn.ext.latching else []
            dst = _find_or_add2(writer, conn.topic, msgtype, qos, typestore=dst_store)
            return dst, partial(dst_store.ros1_to_cdr, typename=msgtype)
        assert isinstance(conn.ext, ConnectionExtRosbag2)
        dst_store = self._dst_store(store, conn.msgtype, conn.msgtype)
        latching = int(any(q.durability.value == 1 for q in conn.ext.offered_qos_profiles))
        dst = _find_or_add1(
            writer, conn.topic, conn.msgtype, typestore=dst_store, callerid=None, latching=latching
        )
        return dst, partial(store.cdr_to_ros1, typename=conn.msgtype)

    def _dst_store(self, src: Typestore, src_msgtype: str, dst_msgtype: str) -> Typestore:
        return self._dst_stores.store_for(src, src_msgtype, dst_msgtype)

    def close(self) -> None:
        with _writing(self.output.path):
            self.writer.close()

    def abort(self) -> None:
        with suppress(Exception):  # already failing; the temporary output is removed anyway
            self.writer.abort()


def _identity(data: Any) -> Any:
    return data


def _find_or_add1(writer: Any, topic: str, msgtype: str, **kwargs: Any) -> Connection:
    for conn in writer.connections:
        ext = conn.ext
        if (conn.topic, conn.msgtype, ext.callerid, ext.latching) == (
            topic,
            msgtype,
            kwargs.get("callerid"),
            kwargs.get("latching"),
        ):
            return conn  # type: ignore[no-any-return]
    return writer.add_connection(topic, msgtype, **kwargs)  # type: ignore[no-any-return]


def _find_or_add2(writer: Any, topic: str, msgtype: str, qos: Sequence[Any], **kwargs: Any) -> Connection:
    for conn in writer.connections:
        if conn.topic == topic and conn.msgtype == msgtype:
            return conn  # type: ignore[no-any-return]
    return writer.add_connection(topic, msgtype, offered_qos_profiles=list(qos), **kwargs)  # type: ignore[no-any-return]


@contextmanager
def _writing(path: Path) -> Iterator[None]:
    try:
        yield
    except RostoolError:
        raise
    except (OSError, ValueError, KeyError, AssertionError) as err:
        raise RostoolError(f"{path}: cannot write: {describe(err)}") from err
    except Exception as err:
        if type(err).__name__ in ("WriterError", "Error") or "sqlite" in type(err).__module__:
            raise RostoolError(f"{path}: cannot write: {describe(err)}") from err
        raise
