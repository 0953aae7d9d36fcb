"""Message types for the rclpy backend: the Python classes rclpy imports (it needs one per publisher and
subscription), and their twins in rosbags' store, which makes and reads every byte.

A type rosbags' distro store lacks is described to it from the imported class itself
(`get_fields_and_field_types()`), so whatever rclpy can import, rostool can decode and encode too.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.rclpy.select import WAY_OUT

_PRIMITIVES = {"boolean": "bool", "octet": "byte", "float": "float32", "double": "float64"}
_SEQUENCE = re.compile(r"sequence<(.+?)(?:, (\d+))?>")
_ARRAY = re.compile(r"(.+)\[(\d+)\]")
_BOUNDED_STRING = re.compile(r"(w?string)<(\d+)>")


def python_class(store_name: str) -> Any:
    """The rclpy message class of `pkg/msg/Type` (or `pkg/srv/...`), or one line naming the package and the
    two ways out."""
    pkg, kind, name = store_name.split("/")
    try:
        module = importlib.import_module(f"{pkg}.{kind}")
    except Exception:
        raise RostoolError(
            f"type {store_name}: rclpy cannot import the Python package {pkg!r} here; source the workspace "
            f"that builds {pkg}, or {WAY_OUT}, which reads .msg sources and asks publishers for their types"
        ) from None
    found = getattr(module, name, None)
    if found is None and "_" in name:  # an action's parts (`Fibonacci_Goal`) live in its own module only
        base = getattr(module, name.partition("_")[0], None)
        if base is not None:
            found = getattr(importlib.import_module(base.__module__), name, None)
    if found is None:
        raise RostoolError(f"unknown type {store_name}: the {pkg} package rclpy imports has no {kind} {name}")
    return found


def ensure_known(types: Any, store_name: str) -> None:
    """Make `store_name` known to rosbags' store (`types`: a ros2 TypeSupport), from source files as the DDS
    backend finds them, else from the class rclpy imports."""
    if types.knows(store_name):
        return
    from rosbags.typesys import get_types_from_msg

    fields, nested = describe(python_class(store_name))
    for inner in nested:
        ensure_known(types, inner)
    text = "\n".join(f"{kind} {name}" for name, kind in fields)
    try:
        types.register(_renamed(get_types_from_msg(text, store_name)))
    except Exception as err:  # a field rosbags' .msg reader does not take (wstring)
        raise RostoolError(
            f"type {store_name}: rostool cannot describe the class rclpy imports to rosbags "
            f"({' '.join(str(err).split())[:120]}); {WAY_OUT} with its .msg sources (--interfaces)"
        ) from None
    defaults = default_values(python_class(store_name), fields)
    if defaults:
        types.sources.defaults[store_name] = defaults


def _renamed(found: Any) -> Any:
    """rosbags' .msg reader files `pkg/srv/X` (and `pkg/action/X`) under `pkg/srv/msg/X`: back to the names
    rmw and the DDS backend use, in the keys and in the field types alike."""
    if isinstance(found, str):
        return found.replace("/srv/msg/", "/srv/").replace("/action/msg/", "/action/")
    if isinstance(found, (tuple, list)):
        return type(found)(_renamed(item) for item in found)
    if isinstance(found, dict):
        return {_renamed(key): _renamed(value) for key, value in found.items()}
    return found


def default_values(cls: Any, fields: list[tuple[str, str]]) -> dict[str, Any]:
    """The .msg defaults of the plain fields, as a new instance of the class holds them (`topic pub` fills
    missing fields with them, as it does from source files)."""
    instance = cls()
    found: dict[str, Any] = {}
    for name, kind in fields:
        if "/" in kind:
            continue
        value = getattr(instance, name)
        value = value.tolist() if hasattr(value, "tolist") else value
        if isinstance(value, (bytes, bytearray)):
            value = value[0] if len(value) == 1 and "[" not in kind else list(value)
        elif isinstance(value, (list, tuple)):
            value = [v[0] if isinstance(v, bytes) and len(v) == 1 else v for v in value]
        found[name] = value
    return found


def describe(cls: Any) -> tuple[list[tuple[str, str]], list[str]]:
    """(fields as (name, .msg type), nested message types) of an rclpy message class."""
    fields: list[tuple[str, str]] = []
    nested: list[str] = []
    slots = getattr(cls, "SLOT_TYPES", ())
    for index, (name, idl) in enumerate(cls.get_fields_and_field_types().items()):
        kind, inner = _msg_type(idl)
        full = _namespaced(slots[index]) if index < len(slots) else None
        if full is not None and inner:  # the class knows the nested type's namespace (`pkg/action/X_Goal`)
            kind, inner = kind.replace(inner[0].replace("/msg/", "/"), full), [full]
        fields.append((name, kind))
        nested += inner
    return fields, nested


def _namespaced(slot: Any) -> str | None:
    """`pkg/kind/Name` of a rosidl NamespacedType (also inside a sequence or an array), else None."""
    while hasattr(slot, "value_type"):
        slot = slot.value_type
    namespaces = getattr(slot, "namespaces", None)
    return "/".join([*namespaces, slot.name]) if namespaces and len(namespaces) == 2 else None


def _msg_type(idl: str) -> tuple[str, list[str]]:
    found = _SEQUENCE.fullmatch(idl)
    if found:
        base, nested = _base(found[1])
        return base + (f"[<={found[2]}]" if found[2] else "[]"), nested
    found = _ARRAY.fullmatch(idl)
    if found:
        base, nested = _base(found[1])
        return f"{base}[{found[2]}]", nested
    return _base(idl)


def _base(idl: str) -> tuple[str, list[str]]:
    bounded = _BOUNDED_STRING.fullmatch(idl)
    if bounded:  # rosidl's `string<22>` is .msg's `string<=22>`
        return f"{bounded[1]}<={bounded[2]}", []
    if "/" in idl:
        pkg, _, name = idl.rpartition("/")
        store_name = f"{pkg}/{name}" if pkg.count("/") else f"{pkg}/msg/{name}"
        return idl, [store_name]
    return _PRIMITIVES.get(idl, idl), []


def to_rclpy(types: Any, message: object, store_name: str, cls: Any) -> Any:
    """A rosbags message as an instance of the class rclpy imports, through its CDR bytes."""
    from rclpy.serialization import deserialize_message

    return deserialize_message(types.serialize(message, store_name), cls)


def from_rclpy(types: Any, message: object, store_name: str) -> Any:
    """An rclpy message as rosbags' message of `store_name`, through its CDR bytes. rmw's serialization
    may leave more padding at the end than rosbags' size check allows, so the bytes past the message are
    not checked."""
    from rclpy.serialization import serialize_message

    raw = memoryview(serialize_message(message))
    msgdef = types.store.get_msgdef(store_name)
    read = msgdef.deserialize_cdr_le if raw[1] else msgdef.deserialize_cdr_be
    try:
        found, _end = read(raw[4:], 0, msgdef.cls, types.store)
    except Exception as err:  # struct.error, ValueError: the class and rosbags' description disagree
        raise RostoolError(
            f"type {store_name}: rosbags cannot read what rclpy's class holds ({' '.join(str(err).split())})"
        ) from None
    return found
