"""One topic's table of `bag export`: rows buffered by column and written in batches, to Parquet, CSV or
pyarrow Tables in memory, under a `.partial` name until complete.

Parquet tables gather their batches into row groups of `row_group_rows` rows or `row_group_bytes` bytes
(Arrow's count), as Parquet readers like them: a row group per batch (8,192 rows) made footers of thousands
of row groups, which cost readers and the join of a bag exported in pieces (parquet_concat.py) their Python
time. What one export's tables hold back together stays under a `RowGroupBudget`."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any, Literal, Protocol

from rostool.bag.columnar import columns_from_messages
from rostool.bag.export_columns import Column, arrow_type, is_scalar

TableFormat = Literal["parquet", "csv", "arrow"]  # arrow: pyarrow Tables in memory (ExportResult.tables)


class TableOptions(Protocol):
    fmt: TableFormat | None
    batch_rows: int
    batch_bytes: int
    row_group_rows: int
    row_group_bytes: int
    held_bytes: int


class RowGroupBudget:
    """The bytes of batches that one export's Parquet tables hold back for their next row groups: past
    `limit`, the table holding the most writes its row group early (memory stays bounded with many topics)."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.sinks: list[ParquetSink] = []

    def check(self) -> None:
        while sum(sink.held_bytes for sink in self.sinks) > self.limit:
            max(self.sinks, key=lambda sink: sink.held_bytes).write_group()


class TopicTable:
    """One topic's rows, buffered by column and written in batches."""

    def __init__(
        self,
        msgtype: str,
        columns: list[Column],
        path: Path,
        options: TableOptions,
        decoder: Any = None,
        budget: RowGroupBudget | None = None,
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
        self.sink: ArrowSink | CsvSink
        if options.fmt == "arrow":
            self.sink = MemorySink(columns)
            return
        path.parent.mkdir(parents=True, exist_ok=True)
        if options.fmt == "parquet":
            budget = budget or RowGroupBudget(options.held_bytes)
            self.sink = ParquetSink(
                self.partial, columns, options.row_group_rows, options.row_group_bytes, budget
            )
        else:
            self.sink = CsvSink(self.partial, columns)

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
        assert self.decoder is not None and isinstance(self.sink, ArrowSink)
        for start in range(0, len(batch.starts), self.batch_rows):
            part = slice(start, start + self.batch_rows)
            arrays = self.decoder.decode_slices(batch.buffer, batch.starts[part], batch.sizes[part])
            self.sink.write_arrays(batch.log_times[part], arrays)

    def flush(self) -> None:
        """Raw rows are decoded column-wise; decoded messages give their columns through each attribute once
        per message (columns_from_messages)."""
        if self._raws:
            assert self.decoder is not None and isinstance(self.sink, ArrowSink)
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


class ArrowSink:
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


class MemorySink(ArrowSink):
    def __init__(self, columns: list[Column]) -> None:
        super().__init__(columns)
        self._batches: list[Any] = []

    def write_batch(self, batch: Any) -> None:
        self._batches.append(batch)

    def table(self) -> Any:
        return self._pa.Table.from_batches(self._batches, schema=self.schema)


class ParquetSink(ArrowSink):
    """Batches held until they make a row group (see the module's docstring), then written."""

    def __init__(
        self, path: Path, columns: list[Column], group_rows: int, group_bytes: int, budget: RowGroupBudget
    ) -> None:
        import pyarrow.parquet as pq

        super().__init__(columns)
        pa = self._pa
        # dictionaries only where values repeat by nature (strings, bytes): tried on every float column they
        # cost most of the write time and make the file larger
        texts = [f.name for f in self.schema if pa.types.is_string(f.type) or pa.types.is_binary(f.type)]
        self.writer = pq.ParquetWriter(path, self.schema, compression="zstd", use_dictionary=texts)
        self._closed = False
        self.group_rows, self.group_bytes = group_rows, group_bytes
        self._held: list[Any] = []
        self._held_rows = 0
        self.held_bytes = 0
        self.budget = budget
        budget.sinks.append(self)

    def write_batch(self, batch: Any) -> None:
        self._held.append(batch)
        self._held_rows += batch.num_rows
        self.held_bytes += batch.nbytes
        if self._held_rows >= self.group_rows or self.held_bytes >= self.group_bytes:
            self.write_group()
        else:
            self.budget.check()

    def write_group(self) -> None:
        """What is held as one row group; past `group_rows`, groups of exactly that many, the rest held."""
        if not self._held:
            return
        table = self._pa.Table.from_batches(self._held, schema=self.schema)
        self._held, self._held_rows, self.held_bytes = [], 0, 0
        if table.num_rows > self.group_rows and not self._closed:
            whole = table.num_rows - table.num_rows % self.group_rows
            rest = table.slice(whole)
            table = table.slice(0, whole)
            if rest.num_rows:
                self._held, self._held_rows, self.held_bytes = rest.to_batches(), rest.num_rows, rest.nbytes
        self.writer.write_table(table, row_group_size=min(table.num_rows, self.group_rows) or 1)

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                self.write_group()
            finally:
                self._held, self._held_rows, self.held_bytes = [], 0, 0
                if self in self.budget.sinks:
                    self.budget.sinks.remove(self)
                self.writer.close()


class CsvSink:
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
