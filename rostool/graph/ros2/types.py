"""ROS 2 types on rostool's DDS: dynamic IDL classes for the DDS registration, over the session's types
(rostool.interfaces.ros2_types: rosbags' store for the bytes).

Cyclone needs a registered type to create a topic: an IdlStruct class is built from the rosbags definition
with the name rmw uses (`pkg::msg::dds_::Type_`), final extensibility and the member mapping
rmw_cyclonedds_cpp's dyntype.cpp uses (ROS `char` and `byte` are uint8, bounded strings keep their bound),
so the XTypes type information Cyclone announces matches the one a real ROS 2 node announces and type-aware
matching succeeds. The class is only a type description: samples are never converted to or from it.
"""

from __future__ import annotations

import threading
import types as pytypes
from collections.abc import Sequence
from inspect import get_annotations
from typing import Any

from rosbags.interfaces import Nodetype

from rostool.errors import RostoolError
from rostool.graph.ros2_base.names import type_to_dds
from rostool.interfaces.ros2_types import Ros2Types
from rostool.interfaces.typestores import DEFAULT_DISTRO


def gid_size(distro: str) -> int:
    """rmw_dds_common/msg/Gid is 24 bytes up to Humble, 16 from Iron on."""
    return 24 if distro in ("foxy", "galactic", "humble") else 16


class TypeSupport(Ros2Types):
    """The session's types with the DDS classes rostool's DDS transport registers them under."""

    def __init__(self, distro: str = DEFAULT_DISTRO, interface_paths: Sequence[str] = ()) -> None:
        super().__init__(distro, interface_paths)
        self._classes: dict[str, type] = {}
        self._lock = threading.Lock()

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
