"""ROS 2 message types: rosbags' distro store, types from .msg/.srv/.action sources (definitions.py)
registered under rosidl's names the first time they are needed, and CDR (XCDR1, 4-byte encapsulation
header) bytes, the same bytes an rmw writes and rosbag2 stores. Every ROS 2 transport builds on this."""

from __future__ import annotations

import os
import threading
from collections.abc import Mapping, Sequence
from typing import Any

from rosbags.interfaces import Nodetype

from rostool.errors import RostoolError
from rostool.interfaces.definitions import SourceDefinitions, unknown_type_error
from rostool.interfaces.names import to_store_name
from rostool.interfaces.typestores import DEFAULT_DISTRO, DISTROS, builtin_store

# Distros whose nodes put a type hash (REP 2016) into endpoint USER_DATA.
_TYPE_HASH_DISTROS = ("iron", "jazzy", "kilted")
_KINDS = {"message": "msg", "service": "srv", "action": "action"}
EVENT_INFO = "service_msgs/msg/ServiceEventInfo"


def distro_from_env(env: Mapping[str, str] = os.environ) -> str:
    """ROS_DISTRO when rostool knows it, else the default distro."""
    distro = env.get("ROS_DISTRO", "").strip().lower()
    return distro if distro in DISTROS else DEFAULT_DISTRO


class Ros2Types:
    """The ROS 2 types of one session: the distro store, source files, types registered at run time, and
    their CDR bytes (rosbags' serializer: the bytes an rmw writes and rosbag2 stores)."""

    def __init__(self, distro: str = DEFAULT_DISTRO, interface_paths: Sequence[str] = ()) -> None:
        self.distro = distro
        self.store = self._new_store(distro)
        self.sources = SourceDefinitions(interface_paths)
        self._load_lock = threading.RLock()

    @staticmethod
    def _new_store(distro: str) -> Any:
        """The distro's store."""
        return builtin_store(distro)

    def store_name(self, name: str) -> str:
        """`pkg/Type` or `pkg/msg/Type` -> the store's `pkg/msg/Type`; a clear error when unknown."""
        store_name = to_store_name(name.strip())
        if not self.knows(store_name):
            raise self.unknown("message", name)
        return store_name

    def knows(self, store_name: str) -> bool:
        """Is the type in the store, or in a source file (then it is registered now)?"""
        if self.in_store(store_name):
            return True
        if store_name.endswith("_Event") and "/srv/" in store_name:
            return self._service_event(store_name)
        with self._load_lock:
            typs = self.sources.load(store_name, self.in_store)
            if typs is None:
                return False
            self.register(typs)
            return True

    def _service_event(self, event: str) -> bool:
        """`pkg/srv/T_Event` (service introspection's `<service>/_service_event` topic), built as rosidl
        does from the service's request and response."""
        service, info = event.removesuffix("_Event"), EVENT_INFO
        _as_rosidl_builds(self.store, info)  # before any event type nests it (here, or learned from a node)
        parts = [f"{service}_Request", f"{service}_Response"]
        if not (self.in_store(info) and all(self.knows(part) for part in parts)):
            return False
        fields = [("info", (Nodetype.NAME, info))]
        fields += [(name, (Nodetype.SEQUENCE, ((Nodetype.NAME, part), 1)))
                   for name, part in zip(("request", "response"), parts, strict=True)]  # fmt: skip
        self.register({event: ([], fields)})
        return True

    def in_store(self, store_name: str) -> bool:
        """Known without looking at source files (built in, or registered already)."""
        return store_name in self.store.fielddefs

    def unknown(self, what: str, name: str, built_in: Sequence[str] = ()) -> RostoolError:
        """The error for a type found nowhere, naming every place searched."""
        searched = f"rosbags' built-in ROS 2 {self.distro} type store"
        if built_in:
            searched += f", rostool's built-in {what} types ({', '.join(built_in)})"
        hint = (
            "Point --interfaces (or ROSTOOL_INTERFACES) at the source tree that defines it, or set "
            f"ROS_DISTRO to one of {', '.join(DISTROS)} for another distro's types"
        )
        store_name = to_store_name(name.strip(), _KINDS.get(what, "msg"))
        return unknown_type_error(what, name.strip(), store_name, searched, self.sources, hint)

    def register(self, typs: Mapping[str, Any]) -> None:
        """Add definitions (rosbags' `{name: (consts, fields)}`), e.g. ones a bag stores."""
        missing = {k: v for k, v in typs.items() if k not in self.store.fielddefs}
        if missing:
            self.store.register(missing)

    def with_defaults(self, store_name: str, value: Any) -> Any:
        """`value` (a mapping of fields, nested ones too) completed with the default values source files
        give fields (rosbags' types carry none). Positional values (a list) name every field already."""
        if not self.sources.defaults or not isinstance(value, (dict, type(None))):
            return value
        result = dict(value or {})
        for name, default in self.sources.defaults.get(store_name, {}).items():
            result.setdefault(name, default)
        for name, desc in self.store.fielddefs[store_name][1]:
            nested, is_array = _nested_type(desc)
            if nested is None or not self._has_defaults(nested):
                continue
            if not is_array:
                result[name] = self.with_defaults(nested, result.get(name))
            elif isinstance(result.get(name), list):
                result[name] = [self.with_defaults(nested, item) for item in result[name]]
        return result

    def _has_defaults(self, store_name: str, seen: frozenset[str] = frozenset()) -> bool:
        if store_name in self.sources.defaults:
            return True
        if store_name in seen or store_name not in self.store.fielddefs:
            return False
        nested_types = (_nested_type(desc)[0] for _name, desc in self.store.fielddefs[store_name][1])
        return any(n is not None and self._has_defaults(n, seen | {store_name}) for n in nested_types)

    def type_hash(self, store_name: str) -> str | None:
        if self.distro not in _TYPE_HASH_DISTROS:
            return None
        try:
            return str(self.store.hash_rihs01(store_name))
        except Exception:  # a definition rosbags cannot hash: announce none, as Humble does
            return None

    def user_data(self, store_name: str) -> bytes | None:
        digest = self.type_hash(store_name)
        return f"typehash={digest};".encode() if digest else None

    def serialize(self, message: object, store_name: str) -> bytes:
        raw = bytes(self.store.serialize_cdr(message, store_name))
        # Pad to 4 bytes like rmw writers (and as the RTPS payload would be anyway).
        return raw + b"\0" * (-len(raw) % 4)

    def deserialize(self, raw: bytes | memoryview, store_name: str) -> Any:
        return self.store.deserialize_cdr(bytes(raw), store_name)


def _as_rosidl_builds(store: Any, name: str) -> None:
    """`name`'s `char` fields as `uint8`, as rosidl builds them (a .msg `char` is an IDL `uint8`).

    rosbags keeps .msg `char` as a type of its own and hashes it as one (REP 2016's FIELD_TYPE_CHAR), so its
    ServiceEventInfo (`char[16] client_gid`) hashes to RIHS01_83f84988..., while every Iron+ node announces
    and describes `uint8[16] client_gid` (RIHS01_41bcbbe0..., share/service_msgs/msg/ServiceEventInfo.json).
    Every `pkg/srv/T_Event` nests it: with rosbags' version no event type a node describes passed the
    hash check (type_description.verified), so `service echo` of a type rostool has no source for failed.
    The bytes are the same (one octet each), so decoding is unchanged. Done when an event type is first
    asked for (every way to learn one asks `knows` first), so `interface show` of the message itself still
    prints its .msg's `char[16]`."""
    found = store.fielddefs.get(name)
    if found is None:  # a distro before Iron: no service introspection
        return
    consts, fields = found
    store.fielddefs[name] = (consts, [(field, _char_as_uint8(desc)) for field, desc in fields])
    store.cache.pop(name, None)


def _char_as_uint8(desc: Any) -> Any:
    kind, args = desc
    if kind == Nodetype.BASE and args[0] == "char":
        return (kind, ("uint8", args[1]))
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        return (kind, (_char_as_uint8(args[0]), args[1]))
    return desc


def _nested_type(desc: Any) -> tuple[str | None, bool]:
    """(message type, whether an array or sequence of it) of a rosbags field description."""
    kind, args = desc
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        element_kind, element = args[0]
        return (element if element_kind == Nodetype.NAME else None), True
    return (args if kind == Nodetype.NAME else None), False
