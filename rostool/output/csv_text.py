"""CSV rows of messages, like `rostopic echo -p`: a `%time` column, then one column per leaf field."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from typing import Any

from rostool.output.plain import TIME_TYPES, is_message, message_fields


def _leaves(value: Any, prefix: str) -> Iterator[tuple[str, Any]]:
    if is_message(value):
        if getattr(value, "__msgtype__", "") in TIME_TYPES:
            yield prefix, int(value.sec) * 1_000_000_000 + int(value.nanosec)
            return
        for name, field in message_fields(value):
            yield from _leaves(field, f"{prefix}.{name}")
    elif isinstance(value, str):
        yield prefix, value
    elif hasattr(value, "tolist") or isinstance(value, (list, tuple, bytes, bytearray)):
        items = value.tolist() if hasattr(value, "tolist") else list(value)
        if not isinstance(items, list):
            yield prefix, items
            return
        for index, item in enumerate(items):
            yield from _leaves(item, f"{prefix}{index}")
    elif isinstance(value, dict):
        for name, item in value.items():
            yield from _leaves(item, f"{prefix}.{name}")
    elif isinstance(value, bool):
        yield prefix, int(value)
    else:
        yield prefix, value


class CsvWriter:
    """Writes a header before the first row; `time_ns` is the receive (or record) time."""

    def __init__(self) -> None:
        self._header_written = False

    def row(self, msg: object, time_ns: int) -> str:
        stamp = getattr(getattr(msg, "header", None), "stamp", None)
        if stamp is not None:  # rostopic echo -p prefers the message's own time
            time_ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        return self._write(list(_leaves(msg, "field")), time_ns)

    def row_values(self, values: list[tuple[str, Any]], time_ns: int) -> str:
        """A row of selected fields: each (path, plain value) flattened under its own name."""
        leaves = [leaf for path, value in values for leaf in _leaves(value, path)]
        return self._write(leaves, time_ns)

    def _write(self, leaves: list[tuple[str, Any]], time_ns: int) -> str:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        if not self._header_written:
            writer.writerow(["%time", *(name for name, _ in leaves)])
            self._header_written = True
        writer.writerow([time_ns, *(value for _, value in leaves)])
        return buffer.getvalue().rstrip("\n")
