"""YAML/dict values -> message objects, with defaults for missing fields and clear type errors.

rosbags builds messages from complete keyword arguments only; filling defaults, checking names and
types, and accepting positional values (as `rostopic pub` does) is written here.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

from rostool.errors import RostoolError
from rostool.interfaces.names import to_ros1_name

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

_INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1), "uint8": (0, 2**8 - 1), "byte": (0, 2**8 - 1), "char": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1), "uint64": (0, 2**64 - 1),
}  # fmt: skip
_FLOATS = {"float32", "float64"}
_NUMPY = {
    "int8": np.int8, "uint8": np.uint8, "byte": np.uint8, "char": np.uint8, "int16": np.int16,
    "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32, "int64": np.int64,
    "uint64": np.uint64, "float32": np.float32, "float64": np.float64, "bool": np.bool_,
}  # fmt: skip
_TIME_TYPES = {"builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"}


class FillError(RostoolError):
    pass


def build_message(store: Typestore, type_name: str, value: Any, path: str = "") -> Any:
    """Build `type_name` from a mapping (missing fields get defaults) or a list of positional values."""
    fields = [(n, d) for n, d in store.fielddefs[type_name][1] if n != "structure_needs_at_least_one_member"]
    cls = store.types[type_name]
    if type_name in _TIME_TYPES:
        return _build_time(cls, value, path)
    if value is None:
        value = {}
    if isinstance(value, (list, tuple)):
        if len(value) > len(fields):
            raise FillError(
                f"{_where(path, type_name)} takes {len(fields)} value(s) "
                f"({', '.join(n for n, _ in fields)}), got {len(value)}"
            )
        value = dict(zip((n for n, _ in fields), value, strict=False))
    if not isinstance(value, dict):
        if len(fields) == 1:
            value = {fields[0][0]: value}
        else:
            raise FillError(f"{_where(path, type_name)} expects a mapping of its fields, got {value!r}")
    known = {n for n, _ in fields}
    unknown = [k for k in value if k not in known]
    if unknown:
        fields_text = ", ".join(sorted(known))
        where = _where(path, type_name)
        raise FillError(f"{where} has no field {unknown[0]!r}; its fields are: {fields_text}")
    kwargs = {name: _build_field(store, desc, value.get(name), f"{path}{name}") for name, desc in fields}
    if "structure_needs_at_least_one_member" in dict(store.fielddefs[type_name][1]):
        kwargs["structure_needs_at_least_one_member"] = 0
    return cls(**kwargs)


def _where(path: str, type_name: str) -> str:
    return f"field {path.rstrip('.')!r} ({to_ros1_name(type_name)})" if path else to_ros1_name(type_name)


def _build_time(cls: type, value: Any, path: str) -> Any:
    if value is None:
        return cls(sec=0, nanosec=0)
    if value == "now":
        now = time.time_ns()
        return cls(sec=now // 1_000_000_000, nanosec=now % 1_000_000_000)
    if isinstance(value, dict):
        sec: Any = value.get("secs", value.get("sec", 0))
        nsec: Any = value.get("nsecs", value.get("nanosec", 0))
        return cls(sec=int(sec), nanosec=int(nsec))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        ns = round(value * 1e9)
        return cls(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
    raise FillError(f"field {path!r} is a time: give {{secs: S, nsecs: N}}, seconds, or 'now'; got {value!r}")


def _build_field(store: Typestore, desc: Any, value: Any, path: str) -> Any:
    kind, args = desc
    if kind == Nodetype.BASE:
        return _primitive(args[0], value, path)
    if kind == Nodetype.NAME:
        return build_message(store, args, value, path + ".")
    (sub_kind, sub_args), length = args
    items = [] if value is None else value
    if isinstance(items, (bytes, str)) and sub_kind == Nodetype.BASE and sub_args[0] in ("uint8", "char"):
        items = list(items.encode() if isinstance(items, str) else items)
    if not isinstance(items, (list, tuple)):
        raise FillError(f"field {path!r} is an array; got {value!r}")
    fixed = kind == Nodetype.ARRAY
    if fixed and value is not None and len(items) != length:
        raise FillError(f"field {path!r} holds exactly {length} values, got {len(items)}")
    if sub_kind == Nodetype.BASE:
        prim = sub_args[0]
        values = [_primitive(prim, v, f"{path}[{i}]") for i, v in enumerate(items)]
        if fixed and value is None:
            values = [_primitive(prim, None, path)] * length
        if prim in _NUMPY:
            return np.array(values, dtype=_NUMPY[prim])
        return values
    elements = list(items) if not (fixed and value is None) else [None] * length
    return [build_message(store, sub_args, v, f"{path}[{i}].") for i, v in enumerate(elements)]


def _primitive(prim: str, value: Any, path: str) -> Any:
    if prim in ("string", "bounded_string"):
        if value is None:
            return ""
        if isinstance(value, (dict, list)):
            raise FillError(f"field {path!r} is a string; got {value!r}")
        return value if isinstance(value, str) else str(value)
    if prim == "bool":
        if value is None:
            return False
        if isinstance(value, bool) or value in (0, 1):
            return bool(value)
        raise FillError(f"field {path!r} is a bool; got {value!r}")
    if prim in _FLOATS:
        if value is None:
            return 0.0
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise FillError(f"field {path!r} is a {prim}; got {value!r}")
        return float(value)
    if prim in _INT_RANGES:
        if value is None:
            return 0
        if isinstance(value, bool) or not isinstance(value, int):
            raise FillError(f"field {path!r} is an {prim}; got {value!r}")
        low, high = _INT_RANGES[prim]
        if not low <= value <= high:
            raise FillError(f"field {path!r} is an {prim} ({low}..{high}); {value} is out of range")
        return value
    raise FillError(f"field {path!r} has unsupported type {prim}")
