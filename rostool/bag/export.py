"""`rostool bag export`: one table per topic (Parquet or CSV), streamed in batches; images as PNG or MP4.

Each topic's rows are buffered column by column and decoded every `batch_rows` rows or `batch_bytes`
bytes of messages (CSV lines at once; Parquet row groups of up to `row_group_rows` rows or
`row_group_bytes`, export_tables.py), so memory stays flat on a bag of any size.
Files are written under a `.partial` name and renamed when complete; an interrupted export removes them.
Layout: OUT/TOPIC.parquet for one bag; OUT/TOPIC/bag=NAME/part-0.parquet (a hive-partitioned dataset)
when a bag is exported as part of several (`partition`). TOPIC is the topic name without its leading
slash, with `/` replaced by `.` (`/turtle1/cmd_vel` -> `turtle1.cmd_vel`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from rostool.bag.export_columns import TypePlan
from rostool.bag.export_tables import MemorySink, RowGroupBudget, TableFormat, TopicTable
from rostool.bag.failures import warn
from rostool.errors import RostoolError
from rostool.interfaces.typestores import DEFAULT_DISTRO

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
    row_group_rows: int = 1 << 20  # a Parquet row group: this many rows or bytes, whichever comes first
    row_group_bytes: int = 64 * 1024 * 1024
    held_bytes: int = 256 * 1024 * 1024  # what one export's Parquet tables hold back for row groups, at most


@dataclass
class ExportResult:
    bag: str
    messages: int = 0
    bytes: int = 0
    files: list[str] = field(default_factory=list)
    pieces: list[str] = field(default_factory=list)  # a piece's tables, for the caller to join (join_pieces)
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


def table_path(
    out: Path, topic: str, fmt: TableFormat, partition: str | None, piece: int | None = None
) -> Path:
    """Where a topic's table goes; a piece of a bag (see `export_bag`) writes beside it, to be joined."""
    if partition is None:
        where = out / f"{topic_file(topic)}.{fmt}"
    else:
        where = out / topic_file(topic) / f"bag={partition}" / f"part-0.{fmt}"
    return where if piece is None else where.with_name(f"{where.name}{PIECE_SUFFIX}{piece:05d}")


PIECE_SUFFIX = ".piece-"


def export_bag(
    path: Path | str,
    options: ExportOptions,
    partition: str | None = None,
    progress: bool = False,
    piece: tuple[int, int] | None = None,
) -> ExportResult:
    """Export one bag; `partition` (the bag's name) selects the dataset layout for several bags;
    `progress` shows a bar over the messages on stderr. `piece` (k, n): export only the k-th of n runs of
    the bag's chunks, into piece files (`result.pieces`) that `join_pieces` makes the bag's tables; where a
    bag cannot be cut (not an indexed .mcap read chunk-wise, or a topic of several types) piece 0 exports it
    all and the others nothing."""
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
        tables: dict[str, TopicTable] = {}
        images: dict[str, Any] = {}
        skipped: set[str] = set()
        bar = _Bar(sum(conn.msgcount for conn in conns), str(path)) if progress else None
        raw_tables = options.fmt in _COLUMNAR  # decoded column-wise in batches (columnar.py)
        try:
            chunked = _chunk_plan(reader, conns, options)
            if piece is not None:
                if chunked is None or _several_types(conns):  # not cut: piece 0 exports it whole
                    if piece[0]:
                        return result
                    piece = None
                else:
                    chunked = chunked.share(*piece)
            at = piece[0] if piece is not None else None
            new_table = partial(
                _new_table, reader, options, style, partition, at, RowGroupBudget(options.held_bytes)
            )
            if chunked is not None:
                _export_chunks(reader, chunked, tables, new_table, result, bar)
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
                    table = tables[topic] = new_table(conn)
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
                _empty_tables(reader, conns, tables, options, style, partition, at)
            for topic, table in tables.items():
                if isinstance(table.sink, MemorySink):
                    table.flush()
                    result.tables[topic] = table.sink.table()
                else:
                    (result.files if at is None else result.pieces).append(str(table.close()))
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


def _several_types(conns: Sequence[Any]) -> bool:
    """Whether a topic has messages of several types (its table then depends on which comes first)."""
    return len({conn.topic for conn in conns}) < len({(conn.topic, conn.msgtype) for conn in conns})


def _new_table(
    reader: Any,
    options: ExportOptions,
    style: Any,
    partition: str | None,
    piece: int | None,
    budget: RowGroupBudget,
    conn: Any,
) -> TopicTable:
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
    where = table_path(options.out, conn.topic, options.fmt, partition, piece)
    return TopicTable(conn.msgtype, columns, where, options, decoder, budget)


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
    tables: dict[str, TopicTable],
    new_table: Callable[[Any], TopicTable],
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
            table = tables[conn.topic] = new_table(conn)
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
    tables: dict[str, TopicTable],
    options: ExportOptions,
    style: Any,
    partition: str | None,
    piece: int | None,
) -> None:
    """Topics without messages still get a table (with its columns) when their type is known."""
    assert options.fmt is not None and options.out is not None
    fielddefs = reader.resolver.store.fielddefs
    for conn in conns:
        if conn.topic in tables or conn.msgtype not in fielddefs:
            continue
        plan = TypePlan(fielddefs, style, reader.ros_version)
        where = table_path(options.out, conn.topic, options.fmt, partition, piece)
        tables[conn.topic] = TopicTable(conn.msgtype, plan.columns(conn.msgtype), where, options)


def _image_sink(options: ExportOptions, topic: str, partition: str | None) -> Any:
    from rostool.bag.export_images import ImageSink

    assert options.images is not None
    base = options.images / f"bag={partition}" if partition is not None else options.images
    return ImageSink(base, topic_file(topic), topic, video=options.video)


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


def join_pieces(pieces: Sequence[str]) -> list[str]:
    """The tables of a bag exported in pieces: each topic's piece files joined in order (parquet_concat)
    into the file one export would have written, and removed."""
    from rostool.bag.parquet_concat import concat

    by_table: dict[str, list[str]] = {}
    for name in sorted(pieces):  # the piece number is zero-padded: sorted is in piece order
        by_table.setdefault(name[: name.rindex(PIECE_SUFFIX)], []).append(name)
    for table, names in by_table.items():
        partial = Path(table + ".partial")
        try:
            concat([Path(name) for name in names], partial)
            partial.replace(table)
        finally:
            partial.unlink(missing_ok=True)
        for name in names:
            Path(name).unlink(missing_ok=True)
    return list(by_table)
