"""Columnar decoding: a batch of one topic's raw messages straight into Arrow columns, without a Python object
per message.

Most topics repeat one byte layout: fixed-size fields, and strings or sequences whose lengths repeat (an Imu's
`header.frame_id`, a JointState's joint names). For such a batch every field sits at the same offset in every
message, so a numpy view with the message size as stride reads one field of all messages at once. A layout is
taken from one message (the probe) by walking its definition as rosbags' deserializers do (CDR alignment
included); messages of the same size whose length fields agree with the probe's share it, the rest get a
probe of their own, and what is left after a few probes (or a type with sequences of messages, or big-endian
CDR) is deserialized by rosbags one message at a time. rosbags has no batch decoder: this is what it lacks.

The columns and values are those of `export_columns.TypePlan` (the same names, types and values as the
per-message path), which tests check against rosbags for every bag in the test data.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from operator import attrgetter
from typing import Any, NamedTuple

import numpy as np

from rostool.bag.export_columns import TIME_TYPES, Column, TypePlan, arrow_type

MAX_PROBES = 4  # layouts tried per batch before the rest is decoded message by message
_SIZES = {
    "bool": 1, "int8": 1, "uint8": 1, "byte": 1, "char": 1, "octet": 1, "int16": 2, "uint16": 2,
    "int32": 4, "uint32": 4, "float32": 4, "int64": 8, "uint64": 8, "float64": 8,
}  # fmt: skip
_CDR_LE = b"\x00\x01"
_PLACEHOLDER = "structure_needs_at_least_one_member"


class NotColumnar(Exception):
    """This message's layout cannot be read column-wise (it is decoded message by message)."""


class _Scalar(NamedTuple):
    offset: int
    dtype: str  # numpy dtype of the field on the wire


class _Bytes(NamedTuple):
    """A string (decoded as UTF-8) or a byte array: `length` bytes at `offset`."""

    offset: int
    length: int


class _PrimitiveList(NamedTuple):
    offset: int
    count: int
    dtype: str


class _StringList(NamedTuple):
    items: tuple[_Bytes, ...]


class _Stamp(NamedTuple):
    sec: _Scalar
    nanosec: _Scalar


Field = _Scalar | _Bytes | _PrimitiveList | _StringList | _Stamp


@dataclass
class Layout:
    """Where each column's value lies in messages of `size` bytes, and the length fields that must read
    `lengths` in a message for it to have this layout."""

    size: int
    fields: dict[tuple[str, ...], Field]
    lengths: list[tuple[int, int]]  # (offset of a uint32 length, its value in the probe)
    terminators: list[int]  # offsets of CDR strings' NUL bytes


class _Walker:
    """Follows one message through its definition, recording offsets (rosbags' deserializers' rules)."""

    def __init__(self, plan: TypePlan, data: bytes, cdr: bool) -> None:
        self.plan = plan
        self.data = data
        self.cdr = cdr
        self.start = 4 if cdr else 0  # CDR aligns relative to the payload after the encapsulation header
        self.pos = self.start
        self.fields: dict[tuple[str, ...], Field] = {}
        self.lengths: list[tuple[int, int]] = []
        self.terminators: list[int] = []

    def align(self, size: int) -> None:
        if self.cdr:
            size = min(size, 8)
            self.pos += -(self.pos - self.start) % size

    def length(self) -> int:
        self.align(4)
        if self.pos + 4 > len(self.data):
            raise NotColumnar
        value = int.from_bytes(self.data[self.pos : self.pos + 4], "little")
        self.lengths.append((self.pos, value))
        self.pos += 4
        return value

    def scalar(self, typename: str) -> _Scalar:
        size = _SIZES.get(typename)
        if size is None:
            raise NotColumnar
        self.align(size)
        dtype = _DTYPES[self.plan.base(typename)]
        field = _Scalar(self.pos, dtype)
        self.pos += size
        return field

    def string(self) -> _Bytes:
        count = self.length()
        if self.cdr:
            if count < 1:
                raise NotColumnar
            self.terminators.append(self.pos + count - 1)
            field = _Bytes(self.pos, count - 1)
        else:
            field = _Bytes(self.pos, count)
        self.pos += count
        if self.pos > len(self.data):
            raise NotColumnar
        return field

    def message(self, msgtype: str, prefix: tuple[str, ...]) -> None:
        for name, desc in self.plan.fielddefs[msgtype][1]:
            if name == _PLACEHOLDER:  # an empty message: one byte in CDR, nothing in ROS 1; not a column
                if self.cdr:
                    self.scalar("uint8")
                continue
            self.field((*prefix, name), desc)

    def field(self, path: tuple[str, ...], desc: Any) -> None:
        kind, rest = desc
        if kind == 1:
            if rest[0] in ("string", "wstring"):
                if rest[0] == "wstring":
                    raise NotColumnar
                self.fields[path] = self.string()
            else:
                self.fields[path] = self.scalar(rest[0])
        elif kind == 2 and rest in TIME_TYPES:
            sec, nanosec = self.scalar("int32"), self.scalar("uint32")
            self.fields[(*path, "sec")] = sec
            self.fields[(*path, "nanosec")] = nanosec
            self.fields[path] = _Stamp(sec, nanosec)
        elif kind == 2:
            self.message(rest, path)
        else:
            self.array(path, kind, rest)

    def array(self, path: tuple[str, ...], kind: int, rest: Any) -> None:
        element, bound = rest
        count = bound if kind == 3 else self.length()
        if element[0] != 1:
            raise NotColumnar  # sequences of messages: lists of structs, decoded per message
        typename = element[1][0]
        if typename in ("string", "wstring"):
            if typename == "wstring":
                raise NotColumnar
            self.fields[path] = _StringList(tuple(self.string() for _ in range(count)))
            return
        size = _SIZES.get(typename)
        if size is None:
            raise NotColumnar
        if count:
            self.align(size)
        if self.plan.is_bytes(element):
            self.fields[path] = _Bytes(self.pos, count)
        else:
            self.fields[path] = _PrimitiveList(self.pos, count, _DTYPES[self.plan.base(typename)])
        self.pos += count * size
        if self.pos > len(self.data):
            raise NotColumnar


_DTYPES = {
    "bool": "u1", "int8": "i1", "uint8": "u1", "int16": "<i2", "uint16": "<u2", "int32": "<i4",
    "uint32": "<u4", "int64": "<i8", "uint64": "<u8", "float32": "<f4", "float64": "<f8",
}  # fmt: skip


def probe(plan: TypePlan, msgtype: str, data: bytes, cdr: bool) -> Layout:
    """The layout of `data` (raises NotColumnar when it has none a column view can read)."""
    if cdr and data[:2] != _CDR_LE:
        raise NotColumnar  # big-endian CDR: rare, left to rosbags
    walker = _Walker(plan, data, cdr)
    walker.message(msgtype, ())
    if not 0 <= len(data) - walker.pos <= (3 if cdr else 0):
        raise NotColumnar  # trailing bytes: left to rosbags to judge
    return Layout(len(data), walker.fields, walker.lengths, walker.terminators)


class ColumnarDecoder:
    """Decodes batches of one type's raw messages into the pyarrow arrays of `columns` (after the receive
    time, which the caller has). `deserialize` decodes one message for the rows no layout fits."""

    def __init__(
        self,
        plan: TypePlan,
        msgtype: str,
        columns: Sequence[Column],
        cdr: bool,
        deserialize: Callable[[bytes], Any],
    ) -> None:
        import pyarrow as pa

        self._pa = pa
        self.plan = plan
        self.msgtype = msgtype
        self.columns = list(columns)
        self.types = [arrow_type(column.spec) for column in self.columns]
        self.cdr = cdr
        self.deserialize = deserialize
        self.columnar_rows = 0
        self.fallback_rows = 0
        self._layouts: dict[int, list[Layout]] = {}  # by message size: layouts seen before

    def decode(self, datas: Sequence[bytes | memoryview]) -> list[Any]:
        """One pyarrow array per column, rows in the order of `datas`."""
        pa = self._pa
        sizes = np.fromiter(map(len, datas), dtype=np.int64, count=len(datas))
        if len(datas) and sizes.min() == sizes.max():  # the usual batch: one size, most likely one layout
            uniform = self._uniform(datas)
            if uniform is not None:
                return uniform
        remaining = np.arange(len(datas))
        parts: list[tuple[np.ndarray, list[Any]]] = []
        for _ in range(MAX_PROBES):
            if not len(remaining):
                break
            first = int(remaining[0])
            layout = self._layout(datas[first])
            if layout is None:
                break
            rows = remaining[sizes[remaining] == layout.size]
            buffer = np.frombuffer(b"".join([datas[i] for i in rows]), dtype=np.uint8).reshape(len(rows), -1)
            fits = _fits(buffer, layout)
            rows, buffer = rows[fits], buffer[fits]
            arrays = self._arrays(buffer, layout) if len(rows) else None
            if arrays is None:  # the probe's own row must not come back forever
                rows = np.array([first])
                arrays = self._fallback(datas, rows)
            else:
                self.columnar_rows += len(rows)
            parts.append((rows, arrays))
            remaining = np.setdiff1d(remaining, rows, assume_unique=True)
        if len(remaining):
            parts.append((remaining, self._fallback(datas, remaining)))
        if len(parts) == 1 and np.array_equal(parts[0][0], np.arange(len(datas))):
            return parts[0][1]
        order = np.argsort(np.concatenate([rows for rows, _ in parts]), kind="stable")
        merged = []
        for index in range(len(self.columns)):
            joined = pa.concat_arrays([arrays[index] for _, arrays in parts])
            merged.append(joined.take(pa.array(order)))
        return merged

    def decode_slices(self, buffer: bytes, starts: np.ndarray, sizes: np.ndarray) -> list[Any]:
        """As `decode`, for messages given as slices of one buffer (a chunk's): gathered straight into the
        row-per-message array when they share one size."""
        view = memoryview(buffer)
        if len(starts) and sizes.min() == sizes.max():
            size, first = int(sizes[0]), int(starts[0])
            steps = np.diff(starts)
            if len(steps) and (steps == steps[0]).all() and steps[0] >= size:  # evenly spaced: a strided view
                whole = np.frombuffer(buffer, dtype=np.uint8)
                matrix = np.lib.stride_tricks.as_strided(
                    whole[first:], shape=(len(starts), size), strides=(int(steps[0]), 1), writeable=False
                )
            else:
                joined = b"".join([view[s : s + size] for s in starts.tolist()])
                matrix = np.frombuffer(joined, dtype=np.uint8).reshape(len(starts), size)
            arrays = self._uniform_rows(matrix, bytes(view[first : first + size]))
            if arrays is not None:
                return arrays
        return self.decode([view[s : s + n] for s, n in zip(starts.tolist(), sizes.tolist(), strict=True)])

    def _uniform(self, datas: Sequence[bytes | memoryview]) -> list[Any] | None:
        """The batch's columns when every message has the first one's layout; None otherwise."""
        buffer = np.frombuffer(b"".join(datas), dtype=np.uint8).reshape(len(datas), -1)
        return self._uniform_rows(buffer, bytes(datas[0]))

    def _uniform_rows(self, buffer: np.ndarray, first: bytes) -> list[Any] | None:
        layout = self._layout(first)
        if layout is None or not _fits(buffer, layout).all():
            return None
        arrays = self._arrays(buffer, layout)
        if arrays is not None:
            self.columnar_rows += len(buffer)
        return arrays

    def _layout(self, data: bytes | memoryview) -> Layout | None:
        known = self._layouts.setdefault(len(data), [])
        for layout in known:
            if all(int.from_bytes(data[o : o + 4], "little") == v for o, v in layout.lengths):
                return layout
        try:
            layout = probe(self.plan, self.msgtype, bytes(data), self.cdr)
        except (NotColumnar, IndexError):
            return None
        if len(known) < MAX_PROBES:
            known.append(layout)
        return layout

    def _arrays(self, buffer: np.ndarray, layout: Layout) -> list[Any] | None:
        """Every column of the rows in `buffer` (one message a row); None when a value is not what rosbags
        would accept (a string that is not UTF-8, a missing terminator): those rows go message by message."""
        pa = self._pa
        if layout.terminators and buffer[:, layout.terminators].any():
            return None
        arrays = []
        for column, arrow in zip(self.columns, self.types, strict=True):
            field = layout.fields.get(column.path)
            if field is None:
                return None
            array = _column(pa, buffer, field, arrow)
            if array is None:
                return None
            arrays.append(array)
        return arrays

    def _fallback(self, datas: Sequence[bytes], rows: np.ndarray) -> list[Any]:
        self.fallback_rows += len(rows)
        messages = [self.deserialize(datas[int(i)]) for i in rows]
        values = columns_from_messages(self.columns, messages)
        return [self._pa.array(v, type=t) for v, t in zip(values, self.types, strict=True)]


def _fits(buffer: np.ndarray, layout: Layout) -> np.ndarray:
    """Which rows read the probe's value at every length field."""
    fits = np.ones(len(buffer), dtype=bool)
    for offset, value in layout.lengths:
        fits &= buffer[:, offset : offset + 4].copy().view("<u4").ravel() == value
    return fits


def _view(buffer: np.ndarray, offset: int, dtype: str, count: int = 1) -> np.ndarray:
    """`count` values of `dtype` at `offset` of every row, as a contiguous (rows, count) array."""
    size = np.dtype(dtype).itemsize
    return np.ascontiguousarray(buffer[:, offset : offset + size * count]).view(dtype)


def _column(pa: Any, buffer: np.ndarray, field: Field, arrow: Any) -> Any:
    rows = len(buffer)
    if isinstance(field, _Stamp):
        sec = _view(buffer, field.sec.offset, field.sec.dtype).ravel().astype(np.int64)
        nanosec = _view(buffer, field.nanosec.offset, field.nanosec.dtype).ravel().astype(np.int64)
        return pa.array(sec * 1_000_000_000 + nanosec, type=arrow)
    if isinstance(field, _Scalar):
        values = _view(buffer, field.offset, field.dtype).ravel()
        if pa.types.is_boolean(arrow):
            values = values != 0
        return pa.array(values, type=arrow)
    if isinstance(field, _Bytes):
        data = np.ascontiguousarray(buffer[:, field.offset : field.offset + field.length])
        return _binary(pa, arrow, rows, _offsets(rows, field.length), data)
    if isinstance(field, _PrimitiveList):
        values = _view(buffer, field.offset, field.dtype, field.count).reshape(-1)
        if pa.types.is_boolean(arrow.value_type):
            values = values != 0
        values = pa.array(values, type=arrow.value_type)
        return pa.ListArray.from_arrays(pa.array(_offsets(rows, field.count)), values)
    count = len(field.items)
    pieces = [np.ascontiguousarray(buffer[:, s.offset : s.offset + s.length]) for s in field.items]
    data = np.concatenate(pieces, axis=1) if pieces else np.zeros((rows, 0), dtype=np.uint8)
    lengths = np.tile(np.array([s.length for s in field.items], dtype=np.int32), rows)
    string_offsets = np.zeros(rows * count + 1, dtype=np.int32)
    np.cumsum(lengths, out=string_offsets[1:])
    strings = _binary(pa, arrow.value_type, rows * count, string_offsets, data)
    if strings is None:
        return None
    return pa.ListArray.from_arrays(pa.array(_offsets(rows, count)), strings)


def _offsets(rows: int, step: int) -> np.ndarray:
    """Arrow offsets of `rows` items of `step` values each."""
    return np.arange(rows + 1, dtype=np.int32) * np.int32(step)


def _binary(pa: Any, arrow: Any, length: int, offsets: np.ndarray, data: np.ndarray) -> Any:
    array = pa.Array.from_buffers(arrow, length, [None, pa.py_buffer(offsets), pa.py_buffer(data.tobytes())])
    if pa.types.is_string(arrow):
        try:
            array.validate(full=True)  # UTF-8, as rosbags' decode() demands
        except pa.ArrowInvalid:
            return None
    return array


def columns_from_messages(columns: Sequence[Column], messages: list[Any]) -> list[list[Any]]:
    """Each column's values from decoded messages (rosbags' objects), each attribute read once per message:
    columns under one parent (`pose.position.x`, `.y`, `.z`) share the parent's list."""
    lists: dict[tuple[str, ...], list[Any]] = {(): messages}
    out = []
    for column in columns:
        got = _values(lists, column.path)
        out.append(got if column.convert is None else list(map(column.convert, got)))
    return out


def _values(lists: dict[tuple[str, ...], list[Any]], path: tuple[str, ...]) -> list[Any]:
    """The values at `path`, from (and into) `lists`. Not a closure: a recursive closure is a reference
    cycle that kept each batch's decoded messages alive until a full collection (more than half the CPU
    of exporting tf2_msgs/TFMessage went to those collections)."""
    found = lists.get(path)
    if found is None:
        found = lists[path] = list(map(attrgetter(path[-1]), _values(lists, path[:-1])))
    return found
