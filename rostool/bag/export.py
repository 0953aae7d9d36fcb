"""`rostool bag export`: one table per topic (Parquet or CSV), streamed in batches; images as PNG or MP4.

Each topic's rows are buffered column by column and written every `batch_rows` rows or `batch_bytes`
bytes of messages (a Parquet row group, or CSV lines), so memory stays flat on a bag of any size.
Files are written under a `.partial` name and renamed when complete; an interrupted export removes them.
Layout: OUT/TOPIC.parquet for one bag; OUT/TOPIC/bag=NAME/part-0.parquet (a hive-partitioned dataset)
when a bag is exported as part of several (`partition`). TOPIC is the topic name without its leading
slash, with `/` replaced by `.` (`/turtle1/cmd_vel` -> `turtle1.cmd_vel`).
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from rostool.bag.columnar import columns_from_messages
from rostool.bag.export_columns import Column, TypePlan, arrow_type, is_scalar
from rostool.bag.failures import warn
from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO

TableFormat = Literal["parquet", "csv", "arrow"]  # arrow: pyarrow Tables in memory (ExportResult.tables)
_COLUMNAR = ("parquet", "arrow")
EXTRA_HINT = "pip install 'rostool[export]'"
IMAGE_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")


@dataclass
class ExportOptions:
    fmt: TableFormat | None  # None: images only
    out: Path | None
    topics: Sequence[str] = ()
    images: Path | None = None
    video: bool = False
    distro: str = DEFAULT_DISTRO
    batch_rows: int = 8192
    batch_bytes: int = 32 * 1024 * 1024


@dataclass
class ExportResult:
    bag: str
    messages: int = 0
    bytes: int = 0
    files: list[str] = field(default_factory=list)
    tables: dict[str, Any] = field(default_factory=dict)  # topic -> pyarrow.Table, for the "arrow" format
    images: int = 0


def require_extras(options: ExportOptions) -> None:
    """One line naming the extra when a module the chosen outputs need does not import."""
    import importlib

    needs = []
    if options.fmt in _COLUMNAR:
        needs.append(("pyarrow", "--format parquet"))
    if options.images is not None:
        needs += [("numpy", "--images"), ("PIL", "--images")]
    if options.video:
        needs.append(("av", "--video"))
    for module, what in needs:
        try:
            importlib.import_module(module)
        except ImportError as err:
            raise RostoolError(f"{what} needs the {module} module: {EXTRA_HINT}") from err


def topic_file(topic: str) -> str:
    """The file name of a topic, one to one: the leading `/` dropped, each other `/` a `.`, letters,
    digits, `_` and `-` kept, every other byte `%XX` (so `/a/b` -> `a.b`, `/a.b` -> `a%2Eb`); `/` alone
    is `%2F`. A relative name (`a`, in some ROS 2 bags) is the root namespace's `/a`, and so its file."""
    body = topic[1:] if topic.startswith("/") else topic
    if not body:
        return "%2F"
    return "".join(
        "." if char == "/" else char if char in _KEPT else "".join(f"%{b:02X}" for b in char.encode())
        for char in body
    )


_KEPT = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")


def table_path(out: Path, topic: str, fmt: TableFormat, partition: str | None) -> Path:
    if partition is None:
        return out / f"{topic_file(topic)}.{fmt}"
    return out / topic_file(topic) / f"bag={partition}" / f"part-0.{fmt}"


def export_bag(
    path: Path | str, options: ExportOptions, partition: str | None = None, progress: bool = False
) -> ExportResult:
    """Export one bag; `partition` (the bag's name) selects the dataset layout for several bags;
    `progress` shows a bar over the messages on stderr."""
    from rostool.bag.reader import BagReader

    result = ExportResult(str(path))
    with BagReader([path], options.distro) as reader:
        wanted = options.topics
        if partition is not None:  # a fleet: a topic some bags lack is not an error
            wanted = [name for name in wanted if name in reader.topics]
            if options.topics and not wanted:
                return result
        conns = reader.select(wanted)
        if options.fmt is None or options.out is None:  # images only: decode nothing else
            conns = [conn for conn in conns if conn.msgtype in IMAGE_TYPES]
        style = "ros1" if reader.ros_version == 1 else "ros2"
        tables: dict[str, _Table] = {}
        images: dict[str, Any] = {}
        skipped: set[str] = set()
        bar = _Bar(sum(conn.msgcount for conn in conns), str(path)) if progress else None
        raw_tables = options.fmt in _COLUMNAR  # decoded column-wise in batches (columnar.py)
        try:
            chunked = _chunk_plan(reader, conns, options)
            if chunked is not None:
                _export_chunks(reader, chunked, tables, options, style, partition, result, bar)
            for conn, timestamp, data in reader.messages(conns) if conns and chunked is None else ():
                result.messages += 1
                if bar is not None and not result.messages % 1024:
                    bar.update(result.messages)
                result.bytes += len(data)
                topic = conn.topic
                table = tables.get(topic)
                wants_image = conn.msgtype in IMAGE_TYPES and options.images is not None
                msg = None
                if wants_image or table is None or not raw_tables:
                    msg = reader.deserialize(data, conn)  # the first one also settles the type's definition
                if wants_image:
                    sink = images.get(topic)
                    if sink is None:
                        sink = images[topic] = _image_sink(options, topic, partition)
                    result.images += sink.add(msg, timestamp)
                if options.fmt is None or options.out is None:
                    continue
                if table is None:
                    table = tables[topic] = _new_table(reader, conn, options, style, partition)
                elif conn.msgtype != table.msgtype:
                    if topic not in skipped:
                        skipped.add(topic)
                        warn(
                            f"{topic}: left out its {conn.msgtype} messages (the table holds {table.msgtype})"
                        )
                    continue
                if table.decoder is not None:
                    table.add_raw(data, timestamp)
                else:
                    table.add(msg, timestamp, len(data))
            if options.fmt is not None and options.out is not None:
                _empty_tables(reader, conns, tables, options, style, partition)
            for topic, table in tables.items():
                if isinstance(table.sink, _MemorySink):
                    table.flush()
                    result.tables[topic] = table.sink.table()
                else:
                    result.files.append(str(table.close()))
            for sink in images.values():
                result.files.extend(str(p) for p in sink.close())
            if bar is not None:
                bar.stop()
        except BaseException:
            if bar is not None:
                bar.stop()
            for table in tables.values():
                table.discard()
            for sink in images.values():
                sink.discard()
            raise
    return result


def _new_table(reader: Any, conn: Any, options: ExportOptions, style: Any, partition: str | None) -> _Table:
    """A topic's table; Parquet tables decode raw messages column-wise (ColumnarDecoder)."""
    assert options.fmt is not None and options.out is not None
    plan = TypePlan(reader.resolver.store.fielddefs, style, reader.ros_version)
    columns = plan.columns(conn.msgtype)
    decoder = None
    if options.fmt in _COLUMNAR:
        from rostool.bag.columnar import ColumnarDecoder

        def deserialize(data: bytes, conn: Any = conn) -> object:
            return reader.deserialize(data, conn)

        decoder = ColumnarDecoder(plan, conn.msgtype, columns[1:], reader.ros_version == 2, deserialize)
    where = table_path(options.out, conn.topic, options.fmt, partition)
    return _Table(conn.msgtype, columns, where, options, decoder)


def _chunk_plan(reader: Any, conns: Sequence[Any], options: ExportOptions) -> Any:
    """Where the .mcap chunks of a one-bag Parquet export can be read directly (mcap_batches.py): an
    indexed .mcap (or rosbag2 directory of them, not compressed per message) without images to write."""
    if options.fmt not in _COLUMNAR or options.out is None or options.images is not None or not conns:
        return None
    if len(reader.inputs) != 1 or reader.inputs[0].storage != "mcap":
        return None
    bag = reader.inputs[0]
    if reader.message_compressed:
        return None
    from rostool.bag.mcap_batches import plan

    return plan(list(bag.files), {(conn.topic, conn.msgtype): conn for conn in conns})


def _export_chunks(
    reader: Any,
    chunked: Any,
    tables: dict[str, _Table],
    options: ExportOptions,
    style: Any,
    partition: str | None,
    result: ExportResult,
    bar: _Bar | None,
) -> None:
    """Each chunk's messages, channel by channel, straight into their tables."""
    from rostool.bag.mcap_batches import batches

    for conn, batch in batches(chunked):
        table = tables.get(conn.topic)
        if table is None:
            first = batch.buffer[batch.starts[0] : batch.starts[0] + batch.sizes[0]]
            reader.deserialize(first, conn)  # settles the type's definition, as the first message does
            table = tables[conn.topic] = _new_table(reader, conn, options, style, partition)
        elif conn.msgtype != table.msgtype:
            warn(f"{conn.topic}: left out its {conn.msgtype} messages (the table holds {table.msgtype})")
            continue
        table.add_batch(batch)
        result.messages += len(batch.starts)
        result.bytes += int(batch.sizes.sum())
        if bar is not None:
            bar.update(result.messages)


def _empty_tables(
    reader: Any,
    conns: Sequence[Any],
    tables: dict[str, _Table],
    options: ExportOptions,
    style: Any,
    partition: str | None,
) -> None:
    """Topics without messages still get a table (with its columns) when their type is known."""
    assert options.fmt is not None and options.out is not None
    fielddefs = reader.resolver.store.fielddefs
    for conn in conns:
        if conn.topic in tables or conn.msgtype not in fielddefs:
            continue
        plan = TypePlan(fielddefs, style, reader.ros_version)
        where = table_path(options.out, conn.topic, options.fmt, partition)
        tables[conn.topic] = _Table(conn.msgtype, plan.columns(conn.msgtype), where, options)


def _image_sink(options: ExportOptions, topic: str, partition: str | None) -> Any:
    from rostool.bag.export_images import ImageSink

    assert options.images is not None
    base = options.images / f"bag={partition}" if partition is not None else options.images
    return ImageSink(base, topic_file(topic), topic, video=options.video)


class _Table:
    """One topic's rows, buffered by column and written in batches."""

    def __init__(
        self, msgtype: str, columns: list[Column], path: Path, options: ExportOptions, decoder: Any = None
    ) -> None:
        self.msgtype = msgtype
        self.columns = columns
        self.decoder = decoder  # a ColumnarDecoder: rows come as raw bytes (add_raw, add_batch)
        self._raws: list[bytes | memoryview] = []
        self.path = path
        self.partial = path.with_name(path.name + ".partial")
        self.batch_rows = options.batch_rows
        self.batch_bytes = options.batch_bytes
        self._times: list[int] = []
        self._messages: list[object] = []
        self._bytes = 0
        self.sink: _ArrowSink | _CsvSink
        if options.fmt == "arrow":
            self.sink = _MemorySink(columns)
            return
        path.parent.mkdir(parents=True, exist_ok=True)
        self.sink = (_ParquetSink if options.fmt == "parquet" else _CsvSink)(self.partial, columns)

    def add(self, msg: object, timestamp: int, size: int) -> None:
        self._times.append(timestamp)
        self._messages.append(msg)
        self._bytes += size
        if len(self._times) >= self.batch_rows or self._bytes >= self.batch_bytes:
            self.flush()

    def add_raw(self, data: bytes | memoryview, timestamp: int) -> None:
        self._times.append(timestamp)
        self._raws.append(data)
        self._bytes += len(data)
        if len(self._times) >= self.batch_rows or self._bytes >= self.batch_bytes:
            self.flush()

    def add_batch(self, batch: Any) -> None:
        """A chunk's messages of this topic (mcap_batches.ChannelBatch), written as they come."""
        self.flush()
        assert self.decoder is not None and isinstance(self.sink, _ArrowSink)
        for start in range(0, len(batch.starts), self.batch_rows):
            part = slice(start, start + self.batch_rows)
            arrays = self.decoder.decode_slices(batch.buffer, batch.starts[part], batch.sizes[part])
            self.sink.write_arrays(batch.log_times[part], arrays)

    def flush(self) -> None:
        """Raw rows are decoded column-wise; decoded messages give their columns through each attribute once
        per message (columns_from_messages)."""
        if self._raws:
            assert self.decoder is not None and isinstance(self.sink, _ArrowSink)
            self.sink.write_arrays(self._times, self.decoder.decode(self._raws))
        elif self._times:
            self.sink.write([self._times, *columns_from_messages(self.columns[1:], self._messages)])
        self._times, self._messages, self._raws, self._bytes = [], [], [], 0

    def close(self) -> Path:
        self.flush()
        self.sink.close()
        self.partial.replace(self.path)
        return self.path

    def discard(self) -> None:
        try:
            self.sink.close()
        finally:
            self.partial.unlink(missing_ok=True)


class _ArrowSink:
    """Record batches of the columns' schema, to wherever `write_batch` puts them."""

    def __init__(self, columns: list[Column]) -> None:
        import pyarrow as pa

        self._pa = pa
        self.schema = pa.schema([(column.name, arrow_type(column.spec)) for column in columns])

    def write(self, values: list[list[Any]]) -> None:
        pa = self._pa
        arrays = [pa.array(column, type=f.type) for column, f in zip(values, self.schema, strict=True)]
        self.write_batch(pa.RecordBatch.from_arrays(arrays, schema=self.schema))

    def write_arrays(self, times: Any, arrays: list[Any]) -> None:
        pa = self._pa
        columns = [pa.array(times, type=pa.int64()), *arrays]
        self.write_batch(pa.RecordBatch.from_arrays(columns, schema=self.schema))

    def write_batch(self, batch: Any) -> None:
        raise NotImplementedError

    def close(self) -> None:
        pass


class _MemorySink(_ArrowSink):
    def __init__(self, columns: list[Column]) -> None:
        super().__init__(columns)
        self._batches: list[Any] = []

    def write_batch(self, batch: Any) -> None:
        self._batches.append(batch)

    def table(self) -> Any:
        return self._pa.Table.from_batches(self._batches, schema=self.schema)


class _ParquetSink(_ArrowSink):
    def __init__(self, path: Path, columns: list[Column]) -> None:
        import pyarrow.parquet as pq

        super().__init__(columns)
        pa = self._pa
        # dictionaries only where values repeat by nature (strings, bytes): tried on every float column they
        # cost most of the write time and make the file larger
        texts = [f.name for f in self.schema if pa.types.is_string(f.type) or pa.types.is_binary(f.type)]
        self.writer = pq.ParquetWriter(path, self.schema, compression="zstd", use_dictionary=texts)
        self._closed = False

    def write_batch(self, batch: Any) -> None:
        self.writer.write_batch(batch)

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.writer.close()


class _CsvSink:
    """Scalars as text (bool as true/false); byte arrays, arrays and structs as JSON text."""

    def __init__(self, path: Path, columns: list[Column]) -> None:
        self.handle = path.open("w", newline="", encoding="utf-8")
        self.writer = csv.writer(self.handle, lineterminator="\n")
        self.writer.writerow([column.name for column in columns])
        self.convert = [_csv_converter(column) for column in columns]

    def write(self, values: list[list[Any]]) -> None:
        converted = [
            column if convert is None else [convert(value) for value in column]
            for column, convert in zip(values, self.convert, strict=True)
        ]
        self.writer.writerows(zip(*converted, strict=True))

    def close(self) -> None:
        self.handle.close()


def _csv_converter(column: Column) -> Any:
    from rostool.output.json_text import dumps

    if column.spec == "bool":
        return lambda value: "true" if value else "false"
    if is_scalar(column.spec):
        return None
    return lambda value: dumps(_json_ready(value))


def _json_ready(value: Any) -> Any:
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, dict):
        return {key: _json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(item) for item in value]
    return value


class _Bar:
    """A rich progress bar over one bag's messages (transient: gone when the export ends)."""

    def __init__(self, total: int, name: str) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        self._progress = Progress(
            TextColumn("exporting"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
            console=Console(stderr=True), transient=True, redirect_stdout=False,
        )  # fmt: skip
        self._task = self._progress.add_task(name, total=total or None)
        self._progress.start()

    def update(self, done: int) -> None:
        self._progress.update(self._task, completed=done)

    def stop(self) -> None:
        self._progress.stop()
