"""ROS 2 message types: rosbags' distro store for the bytes, dynamic IDL classes for the DDS registration.

A type the distro store lacks is looked up in .msg/.srv/.action source files (definitions.py) and
registered under rosidl's names the first time it is needed.

Payload bytes always come from rosbags' CDR (de)serializer (XCDR1, 4-byte encapsulation header), the same
bytes an rmw writes and rosbag2 stores. Cyclone still needs a registered type to create a topic: an
IdlStruct class is built from the rosbags definition with the name rmw uses (`pkg::msg::dds_::Type_`),
final extensibility and the member mapping rmw_cyclonedds_cpp's dyntype.cpp uses (ROS `char` and `byte`
are uint8, bounded strings keep their bound), so the XTypes type information Cyclone announces matches
the one a real ROS 2 node announces and type-aware matching succeeds. The class is only a type
description: samples are never converted to or from it.
"""

from __future__ import annotations

import os
import threading
import types as pytypes
from collections.abc import Mapping, Sequence
from inspect import get_annotations
from typing import Any

from rosbags.interfaces import Nodetype

from rostool.bag.typestores import DEFAULT_DISTRO, DISTROS, builtin_store
from rostool.errors import RostoolError
from rostool.graph.ros2.definitions import SourceDefinitions, unknown_type_error
from rostool.graph.ros2.names import type_to_dds
from rostool.interfaces.names import to_store_name

# Distros whose nodes put a type hash (REP 2016) into endpoint USER_DATA.
_TYPE_HASH_DISTROS = ("iron", "jazzy", "kilted")


_KINDS = {"message": "msg", "service": "srv", "action": "action"}


def distro_from_env(env: Mapping[str, str] = os.environ) -> str:
    """ROS_DISTRO when rostool knows it, else the default distro."""
    distro = env.get("ROS_DISTRO", "").strip().lower()
    return distro if distro in DISTROS else DEFAULT_DISTRO


def gid_size(distro: str) -> int:
    """rmw_dds_common/msg/Gid is 24 bytes up to Humble, 16 from Iron on."""
    return 24 if distro in ("foxy", "galactic", "humble") else 16


class TypeSupport:
    """Types of one ROS 2 graph session: the distro store, source files, types registered at run time."""

    def __init__(self, distro: str = DEFAULT_DISTRO, interface_paths: Sequence[str] = ()) -> None:
        self.distro = distro
        self.store = builtin_store(distro)
        self.sources = SourceDefinitions(interface_paths)
        self._classes: dict[str, type] = {}
        self._lock = threading.Lock()
        self._load_lock = threading.RLock()

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
        service, info = event.removesuffix("_Event"), "service_msgs/msg/ServiceEventInfo"
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

    def idl_class(self, store_name: str, request_header: bool = False) -> type:
        """The DDS type for `store_name`; with `request_header`, for service requests and replies."""
        with self._lock:
            if not request_header:
                return self._idl_class(store_name)
            key = store_name + "#request_header"
            found = self._classes.get(key)
            if found is None:
                found = self._classes[key] = self._with_request_header(store_name)
            return found

    def _with_request_header(self, store_name: str) -> type:
        """Service samples start with rmw_cyclonedds_cpp's 16-byte header (uint64 guid, int64 seq), and
        cyclonedds-python validates every written and received sample against the topic's XTypes type
        (it cannot create a topic without one). So service types get the header as two leading members.
        rmw_cyclonedds_cpp announces its request/reply types without them; peers that announce no type
        information match by type name, peers that announce it (recent dyntype-based releases) do not."""
        from cyclonedds.idl import types as t

        plain = self._idl_class(store_name)
        header = {"rmw_request_guid": t.uint64, "rmw_request_seq": t.int64}
        return self._make_class(store_name, header | dict(get_annotations(plain)))

    def _idl_class(self, store_name: str) -> type:
        found = self._classes.get(store_name)
        if found is not None:
            return found
        _consts, fields = self.store.fielddefs[store_name]
        cls = self._make_class(store_name, {name: self._field_type(desc) for name, desc in fields})
        self._classes[store_name] = cls
        return cls

    @staticmethod
    def _make_class(store_name: str, annotations: dict[str, Any]) -> type:
        from cyclonedds.idl import IdlStruct
        from cyclonedds.idl.annotations import final

        def body(namespace: dict[str, Any]) -> None:
            namespace["__annotations__"].update(annotations)

        cls = pytypes.new_class(
            store_name.replace("/", "_"), (IdlStruct,), {"typename": type_to_dds(store_name)}, body
        )
        final(cls)
        _set_type_information(cls)
        return cls

    def _field_type(self, desc: Any) -> Any:
        from cyclonedds.idl import types as t

        kind, args = desc
        if kind == Nodetype.BASE:
            prim, bound = args
            if prim in ("string", "wstring"):  # cyclonedds-python has no wide strings; rare in ROS
                return t.bounded_str[bound] if bound else str  # type: ignore[misc]
            return _primitive(prim)
        if kind == Nodetype.NAME:
            return self._idl_class(args)
        element, length = args
        inner = self._field_type(element)
        if kind == Nodetype.ARRAY:
            return t.array[inner, length]  # type: ignore[misc]
        return t.sequence[inner, length] if length else t.sequence[inner]  # type: ignore[misc]


_builder: Any = None  # the type-information builder; False: cyclonedds-python's own


def _set_type_information(cls: Any) -> None:
    """Give `cls` the XTypes type information (TypeInformation and TypeMapping) Cyclone announces, built
    as Fast DDS 3 (Kilted) builds it for ROS types: elements of plain sequences and arrays carry no member
    flags (cyclonedds-python sets TRY_CONSTRUCT1 there). Equal type identifiers match at once; different
    ones make Cyclone fetch the peer's type objects and check assignability, which took seconds or never
    ended (Cyclone rejects Fast DDS 3's type objects unless AllowInvalidTryConstruct, see dds.py).
    Checked against Kilted's announced identifiers of rcl_interfaces, std_srvs and action types."""
    global _builder
    from cyclonedds.idl._support import Endianness

    from rostool.graph.ros2.dds import cyclone_config

    if _builder is None:
        # Cyclone validates our own type objects too: flags of 0 need AllowInvalidTryConstruct
        accepted = "<AllowInvalidTryConstruct>true</AllowInvalidTryConstruct>" in cyclone_config()
        _builder = _make_builder() if accepted else False
    if not _builder:
        return
    idl = cls.__idl__
    idl.populate()
    info, mapping = _builder.process_type(cls)
    idl._xt_data = (info, mapping)
    idl._xt_bytedata = (
        info.serialize(endianness=Endianness.Little, use_version_2=True)[4:],
        mapping.serialize(endianness=Endianness.Little, use_version_2=True)[4:],
    )


def _make_builder() -> Any:
    from cyclonedds.idl import _xt_builder as xb

    xt = xb.xt

    class RosXTBuilder(xb.XTBuilder):  # type: ignore[misc]
        _type_hash_db: dict[Any, Any] = {}  # noqa: RUF012 - its own cache, not the base class's

        @classmethod
        def _xt_type_identifier(cls, name: str, entity: Any, minimal: bool) -> Any:
            found = super()._xt_type_identifier(name, entity, minimal)
            header = getattr(found.value, "header", None)
            if isinstance(header, xt.PlainCollectionHeader):
                header.element_flags = xt.MemberFlag()
            return found

    return RosXTBuilder


def _nested_type(desc: Any) -> tuple[str | None, bool]:
    """(message type, whether an array or sequence of it) of a rosbags field description."""
    kind, args = desc
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        element_kind, element = args[0]
        return (element if element_kind == Nodetype.NAME else None), True
    return (args if kind == Nodetype.NAME else None), False


def _primitive(prim: str) -> Any:
    from cyclonedds.idl import types as t

    table: dict[str, Any] = {
        "bool": bool, "byte": t.uint8, "char": t.uint8, "octet": t.uint8, "uint8": t.uint8,
        "int8": t.int8, "int16": t.int16, "uint16": t.uint16, "int32": t.int32, "uint32": t.uint32,
        "int64": t.int64, "uint64": t.uint64, "float32": t.float32, "float64": t.float64,
    }  # fmt: skip
    try:
        return table[prim]
    except KeyError as err:
        raise RostoolError(f"message field type {prim!r} has no DDS mapping in rostool") from err
