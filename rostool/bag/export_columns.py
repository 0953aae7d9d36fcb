"""A message type as table columns, from its definition (not from values, so every batch has one schema).

Nested fields are flattened to dotted names (`pose.position.x`); Time/Duration fields become two integer
columns named as `bag echo` names them (`secs`/`nsecs` for ROS 1 bags, `sec`/`nanosec` for ROS 2);
byte arrays (uint8[], char[]) are one binary value; other arrays are lists, arrays of
messages lists of structs. `Spec` describes a column's type without pyarrow, so CSV needs no extra.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from rostool.output.plain import TIME_TYPES, TimeStyle

# A column type: a primitive name ("int32", "string", "binary", ...), ("list", Spec) or
# ("struct", ((name, Spec), ...)).
Spec = str | tuple[str, Any]

_PRIMITIVES = {
    "bool": "bool", "int8": "int8", "uint8": "uint8", "int16": "int16", "uint16": "uint16",
    "int32": "int32", "uint32": "uint32", "int64": "int64", "uint64": "uint64", "float32": "float32",
    "float64": "float64", "string": "string", "wstring": "string", "octet": "uint8", "char": "uint8",
    "byte": "int8",  # as rosbags decodes it (ROS 1 and ROS 2)
}  # fmt: skip
_SKIPPED_FIELDS = ("structure_needs_at_least_one_member",)
HEADER = "std_msgs/msg/Header"
TIME_COLUMN = "t"
STAMP_COLUMN = "stamp"


@dataclass(frozen=True)
class Column:
    """`path`: the attributes from the message to the value; `convert` turns that value into one pyarrow
    takes for `spec` (bytes, lists, dicts), None when it already is one."""

    name: str
    spec: Spec
    path: tuple[str, ...]
    convert: Callable[[Any], Any] | None = None


class TypePlan:
    """Turns fielddefs (rosbags' `store.fielddefs`) into columns for one message type."""

    def __init__(self, fielddefs: Mapping[str, Any], style: TimeStyle, ros_version: int) -> None:
        self.fielddefs = fielddefs
        self.style = style
        self.ros_version = ros_version
        self._time_names = ("secs", "nsecs") if style == "ros1" else ("sec", "nanosec")
        self._fields: dict[str, list[tuple[str, Any]]] = {}  # `plain` asks once per nested message
        self._converters: dict[str, Callable[[Any], Any]] = {}

    def fields(self, msgtype: str) -> list[tuple[str, Any]]:
        found = self._fields.get(msgtype)
        if found is None:
            defs = self.fielddefs[msgtype][1]
            found = [(name, desc) for name, desc in defs if name not in _SKIPPED_FIELDS]
            self._fields[msgtype] = found
        return found

    def base(self, name: str) -> str:
        return _PRIMITIVES.get(name, "string")

    def is_bytes(self, element: Any) -> bool:
        return element[0] == 1 and self.base(element[1][0]) == "uint8"  # Nodetype.BASE

    def spec(self, desc: Any) -> Spec:
        """The column type of a field description (Nodetype BASE 1, NAME 2, ARRAY 3, SEQUENCE 4)."""
        kind, rest = desc
        if kind == 1:
            return self.base(rest[0])
        if kind == 2:
            if rest in TIME_TYPES:
                return ("struct", ((self._time_names[0], "int32"), (self._time_names[1], "uint32")))
            members = tuple((name, self.spec(sub)) for name, sub in self.fields(rest))
            # Parquet has no empty struct: an empty message keeps rosbags' placeholder member (always null)
            return ("struct", members or ((_SKIPPED_FIELDS[0], "uint8"),))
        element = rest[0]
        return "binary" if self.is_bytes(element) else ("list", self.spec(element))

    def columns(self, msgtype: str) -> list[Column]:
        """The receive time `t`, the header's `stamp` (when the type has a header), then the fields."""
        fields = self.fields(msgtype)
        names = {name for name, _ in fields}
        time_name = TIME_COLUMN if TIME_COLUMN not in names else f"_{TIME_COLUMN}"
        columns = [Column(time_name, "int64", ())]  # the receive time: not a message field
        header = next((desc for name, desc in fields if name == "header"), None)
        if header == (2, HEADER):
            stamp_name = STAMP_COLUMN if STAMP_COLUMN not in names else f"_{STAMP_COLUMN}"
            columns.append(Column(stamp_name, "int64", ("header", "stamp"), _stamp_ns))
        for name, desc in fields:
            columns.extend(self._flat(name, desc))
        return columns

    def _flat(self, path: str, desc: Any) -> list[Column]:
        kind, rest = desc
        names = tuple(path.split("."))
        if kind == 2 and rest in TIME_TYPES:
            sec, nanosec = self._time_names
            return [
                Column(f"{path}.{sec}", "int32", (*names, "sec")),
                Column(f"{path}.{nanosec}", "uint32", (*names, "nanosec")),
            ]
        if kind == 2:
            return [column for name, sub in self.fields(rest) for column in self._flat(f"{path}.{name}", sub)]
        spec = self.spec(desc)
        if spec == "binary":
            return [Column(path, spec, names, _bytes)]
        if kind == 1 or rest[0][0] == 1:  # numpy arrays and lists of primitives go to pyarrow as they are
            return [Column(path, spec, names)]
        element = rest[0]
        plain = self.converter(element[1]) if element[0] == 2 else self.plain
        return [Column(path, spec, names, lambda items: [plain(item) for item in items])]

    def converter(self, msgtype: str) -> Callable[[Any], Any]:
        """`plain` for messages of one type, its fields' conversions looked up once (sequences of messages
        are the per-message path's bulk: tf2_msgs/TFMessage)."""
        found = self._converters.get(msgtype)
        if found is not None:
            return found
        if msgtype in TIME_TYPES:
            sec, nanosec = self._time_names

            def convert(value: Any) -> Any:
                return {sec: int(value.sec), nanosec: int(value.nanosec)}

        else:
            parts: list[tuple[str, Callable[[Any], Any] | None]] = []
            for name, (kind, rest) in self.fields(msgtype):
                if kind == 2:
                    parts.append((name, self.converter(rest)))
                elif kind == 1:
                    parts.append((name, None))
                elif self.is_bytes(rest[0]):
                    parts.append((name, _bytes))
                elif rest[0][0] == 1:
                    parts.append((name, _list))
                else:
                    sub = self.converter(rest[0][1]) if rest[0][0] == 2 else self.plain
                    parts.append((name, lambda items, sub=sub: [sub(item) for item in items]))

            def convert(value: Any) -> Any:
                return {
                    name: getattr(value, name) if part is None else part(getattr(value, name))
                    for name, part in parts
                }

        self._converters[msgtype] = convert
        return convert

    def plain(self, value: Any) -> Any:
        """A nested message as the dict pyarrow takes for its struct (byte arrays as bytes)."""
        msgtype = getattr(value, "__msgtype__", "")
        if msgtype in TIME_TYPES:
            return {self._time_names[0]: int(value.sec), self._time_names[1]: int(value.nanosec)}
        out: dict[str, Any] = {}
        for name, desc in self.fields(msgtype):
            field = getattr(value, name)
            kind, rest = desc
            if kind == 2:
                out[name] = self.plain(field)
            elif kind == 1:
                out[name] = field
            elif self.is_bytes(rest[0]):
                out[name] = _bytes(field)
            elif rest[0][0] == 1:
                out[name] = field.tolist() if hasattr(field, "tolist") else list(field)
            else:
                out[name] = [self.plain(item) for item in field]
        return out


def _stamp_ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _bytes(value: Any) -> bytes:
    return value.tobytes() if hasattr(value, "tobytes") else bytes(value)


def _list(value: Any) -> list[Any]:
    return value.tolist() if hasattr(value, "tolist") else list(value)


def arrow_type(spec: Spec) -> Any:
    """The pyarrow type of a column spec."""
    import pyarrow as pa

    if isinstance(spec, tuple):
        kind, inner = spec
        if kind == "list":
            return pa.list_(arrow_type(inner))
        return pa.struct([(name, arrow_type(sub)) for name, sub in inner])
    return getattr(pa, "bool_" if spec == "bool" else spec)()


def is_scalar(spec: Spec) -> bool:
    return isinstance(spec, str) and spec != "binary"
