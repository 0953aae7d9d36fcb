"""Message types of a bag: the definitions stored in it, else a built-in ROS 2 type store.

rosbags' AnyReader uses either the stored definitions or a default store, all or nothing. Real bags need
finer choices, written here: rosbag2 bags from before definitions were stored have none; some carry
incomplete ones (a definition without its nested types, or a truncated text) that only fail when a
message is decoded; service-event topics (`pkg/srv/Name_Event`) are stored under the service's name
(`pkg/srv/Name`, request and response separated by `---`) and rosbags does not build the event type.
So each type is resolved on its own: stored definition when complete, else the `--distro` store, and a
type whose stored definition fails on a real message falls back to the built-in one.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

import rostool.interfaces.rosbags_fix  # noqa: F401 - must run before types are registered
from rostool.errors import RostoolError

DISTROS: dict[str, Stores] = {
    "foxy": Stores.ROS2_FOXY,
    "galactic": Stores.ROS2_GALACTIC,
    "humble": Stores.ROS2_HUMBLE,
    "iron": Stores.ROS2_IRON,
    "jazzy": Stores.ROS2_JAZZY,
    "kilted": Stores.ROS2_KILTED,
}
DEFAULT_DISTRO = "jazzy"

Typesdict = dict[str, tuple[list[tuple[str, str, object]], list[tuple[str, object]]]]

# service_msgs/msg/ServiceEventInfo for distros whose store lacks it (it appeared in iron).
_SERVICE_EVENT_INFO = """uint8 REQUEST_SENT = 0
uint8 REQUEST_RECEIVED = 1
uint8 RESPONSE_SENT = 2
uint8 RESPONSE_RECEIVED = 3
uint8 event_type
builtin_interfaces/Time stamp
char[16] client_gid
int64 sequence_number
"""


@dataclass(frozen=True)
class StoredDefinition:
    """A definition text found in a bag: `msg` (ROS .msg / .srv text) or `idl`."""

    name: str
    encoding: str
    text: str


def builtin_store(distro: str) -> Typestore:
    try:
        return get_typestore(DISTROS[distro])
    except KeyError as err:
        known = ", ".join(DISTROS)
        raise RostoolError(f"unknown ROS 2 distro {distro!r} (known: {known})") from err


def ros1_name(msgtype: str) -> str:
    """`pkg/msg/Name` -> `pkg/Name`, as ROS 1 tools print types."""
    return msgtype.replace("/msg/", "/", 1)


def _parse(definition: StoredDefinition, name: str) -> Typesdict:
    if definition.encoding == "idl":
        sep = "=" * 80 + "\n"
        typs: Typesdict = {}
        text = definition.text
        parts = text.split(sep)[1:] if text.startswith(f"{sep}IDL: ") else [text]
        for part in parts:
            body = part.split("\n", 1)[1] if part.startswith("IDL: ") else part
            typs.update(get_types_from_idl(body))  # type: ignore[arg-type]
        return typs
    return get_types_from_msg(definition.text, name)  # type: ignore[return-value]


def _references(fields: Iterable[tuple[str, object]]) -> Iterable[str]:
    for _name, desc in fields:
        node, rest = desc  # type: ignore[misc]
        if node == Nodetype.NAME:
            yield rest
        elif node in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            sub = rest[0]
            if sub[0] == Nodetype.NAME:
                yield sub[1]


def _closure(typs: Mapping[str, object], name: str, known: Mapping[str, object]) -> set[str] | None:
    """Names `name` needs, all found in `typs` or `known`; None when one is missing."""
    seen: set[str] = set()
    todo = [name]
    while todo:
        current = todo.pop()
        if current in seen:
            continue
        seen.add(current)
        entry = typs.get(current) or known.get(current)
        if entry is None:
            return None
        todo.extend(_references(entry[1]))  # type: ignore[index]
    return seen


class TypeResolver:
    """Decodes raw messages of one bag (or several of the same ROS version) with the right definitions."""

    def __init__(
        self,
        msgtypes: Iterable[str],
        stored: Mapping[str, StoredDefinition],
        ros_version: int,
        distro: str = DEFAULT_DISTRO,
    ) -> None:
        self.ros_version = ros_version
        self.distro = distro
        self._builtin: Typestore | None = None
        self._stored_types: dict[str, Typesdict] = {}
        self.unknown: set[str] = set()
        self._from_builtin: set[str] = set()
        self._stored = stored
        self._sources: Any = None  # rostool.interfaces.definitions.SourceDefinitions, made when needed
        for msgtype in sorted(set(msgtypes)):
            typs = self._stored_types_for(msgtype, stored)
            if typs is not None:
                self._stored_types[msgtype] = typs
            elif ros_version == 2 and msgtype in self.builtin.fielddefs:
                self._from_builtin.add(msgtype)
            elif ros_version == 2 and (found := self._from_sources(msgtype)) is not None:
                self._stored_types[msgtype] = found
            else:
                self.unknown.add(msgtype)
        self.store = self._build()
        self._deserialize = self.store.deserialize_ros1 if ros_version == 1 else self.store.deserialize_cdr
        self._fast: dict[str, Callable[[bytes | memoryview], object]] = {}

    @property
    def builtin(self) -> Typestore:
        if self._builtin is None:
            self._builtin = builtin_store(self.distro)
        return self._builtin

    def stored_text(self, msgtype: str) -> str:
        """The definition text stored for `msgtype` (for service events: the service's .srv text)."""
        for name in (msgtype, msgtype.removesuffix("_Event")):
            if name in self._stored:
                return self._stored[name].text
        raise RostoolError(self.missing_message(msgtype))

    def _from_sources(self, msgtype: str) -> Typesdict | None:
        """A type neither stored nor built in, from the .msg/.srv files the live verbs read:
        ROSTOOL_INTERFACES (--interfaces), ROS_PACKAGE_PATH, the workspace around the current folder and
        AMENT_PREFIX_PATH's share/ (a sourced ROS 2 has its packages' interface files there)."""
        from rostool.interfaces.definitions import SourceDefinitions
        from rostool.interfaces.sources import interface_paths_from_env

        if self._sources is None:
            self._sources = SourceDefinitions(interface_paths_from_env())
        known = self.builtin.fielddefs
        try:
            typs = self._sources.load(msgtype, lambda name: name in known)
        except Exception:  # an unreadable or broken source file: the type stays unknown
            return None
        if typs is None:
            return None
        found: Typesdict = dict(typs)  # type: ignore[arg-type]
        base = get_typestore(Stores.EMPTY).fielddefs
        for name in _closure(found, msgtype, {**base, **known}) or ():
            if name not in found and name not in base and name in known:
                found[name] = known[name]  # type: ignore[assignment]
        return found

    def _stored_types_for(self, msgtype: str, stored: Mapping[str, StoredDefinition]) -> Typesdict | None:
        definition = stored.get(msgtype)
        is_event = self.ros_version == 2 and "/srv/" in msgtype and msgtype.endswith("_Event")
        try:
            if is_event:
                typs = self._service_event(msgtype, stored)
            elif definition is not None and definition.text.strip():
                typs = _parse(definition, msgtype)
            elif definition is not None and (self.ros_version == 1 or msgtype not in self.builtin.fielddefs):
                # A stored empty text is a message without fields (e.g. test_msgs/msg/Empty).
                typs = get_types_from_msg("", msgtype)  # type: ignore[assignment]
            else:
                return None
        except Exception:  # a definition rosbags cannot parse: fall back as if absent
            return None
        if typs is None:
            return None
        known = self.builtin.fielddefs if self.ros_version == 2 else {}
        base = get_typestore(Stores.EMPTY).fielddefs
        needed = _closure(typs, msgtype, {**base, **known})
        if needed is None:
            return None
        borrowed = needed - typs.keys() - base.keys()
        if borrowed and msgtype in known:
            return None  # an incomplete stored definition: the built-in one is the better guess
        # Nested types missing from the stored text come from the built-in store.
        for name in borrowed:
            typs[name] = known[name]  # type: ignore[assignment]
        return typs

    def _service_event(self, msgtype: str, stored: Mapping[str, StoredDefinition]) -> Typesdict | None:
        service = msgtype.removesuffix("_Event")
        definition = stored.get(service)
        if msgtype in stored and "---" in stored[msgtype].text:  # as rostool writes them
            definition = stored[msgtype]
        if definition is None or definition.encoding != "msg" or "---" not in definition.text:
            return None
        request, response = _split_srv(definition.text)
        pkg, name = service.split("/srv/")
        # rosbags' .msg parser only knows `pkg/msg/` names: parse there, then move to `pkg/srv/`.
        typs: Typesdict = {}
        typs.update(get_types_from_msg(request, f"{pkg}/msg/{name}_Request"))  # type: ignore[arg-type]
        typs.update(get_types_from_msg(response, f"{pkg}/msg/{name}_Response"))  # type: ignore[arg-type]
        info = "service_msgs/msg/ServiceEventInfo"
        if info not in self.builtin.fielddefs:
            typs.update(get_types_from_msg(_SERVICE_EVENT_INFO, info))  # type: ignore[arg-type]
        event = (
            "service_msgs/ServiceEventInfo info\n"
            f"{name}_Request[<=1] request\n{name}_Response[<=1] response\n"
        )
        typs.update(get_types_from_msg(event, f"{pkg}/msg/{name}_Event"))  # type: ignore[arg-type]
        moved = {
            f"{pkg}/msg/{name}{part}": f"{pkg}/srv/{name}{part}"
            for part in ("_Request", "_Response", "_Event")
        }
        return {
            moved.get(key, key): (consts, [(f, _renamed(desc, moved)) for f, desc in fields])
            for key, (consts, fields) in typs.items()
        }

    def _build(self) -> Typestore:
        store = get_typestore(Stores.EMPTY)
        for msgtype, typs in self._stored_types.items():
            try:
                store.register(typs)  # type: ignore[arg-type]
            except Exception:  # conflicts with an already registered nested type
                self._from_builtin.add(msgtype) if self.ros_version == 2 else self.unknown.add(msgtype)
        for msgtype in sorted(self._from_builtin):
            needed = _closure(self.builtin.fielddefs, msgtype, store.fielddefs) or {msgtype}
            typs = {name: self.builtin.fielddefs[name] for name in needed if name in self.builtin.fielddefs}
            try:
                store.register(typs)
            except Exception:
                self.unknown.add(msgtype)
        return store

    def source(self, msgtype: str) -> str:
        """Where the definition of `msgtype` comes from: `bag`, `<distro> built-in` or `missing`."""
        if msgtype in self.unknown:
            return "missing"
        return f"{self.distro} built-in" if msgtype in self._from_builtin else "bag"

    def deserialize(self, raw: bytes | memoryview, msgtype: str) -> object:
        fast = self._fast.get(msgtype)
        if fast is not None:
            try:
                return fast(raw)
            except Exception:  # the checked path below reports (or recovers from) it
                pass
        try:
            message = self._deserialize(raw, msgtype)
        except Exception as err:
            if msgtype in self.unknown:
                raise RostoolError(self.missing_message(msgtype)) from err
            if self._fall_back(msgtype):
                return self.deserialize(raw, msgtype)
            raise RostoolError(f"cannot decode a {msgtype} message: {err or type(err).__name__}") from err
        self._fast[msgtype] = _fast_decoder(self.store, msgtype, self.ros_version)
        return message

    def missing_message(self, msgtype: str) -> str:
        where = "the bag stores no definition for it"
        if self.ros_version == 2:
            where += (
                f", the {self.distro} built-in type store lacks it (try --distro) and no .msg file defines "
                "it (source the ROS 2 setup that has its package: AMENT_PREFIX_PATH, or ROSTOOL_INTERFACES)"
            )
        return f"cannot decode {msgtype}: {where}"

    def _fall_back(self, msgtype: str) -> bool:
        """Switch `msgtype` from its stored definition to the built-in one; False if impossible."""
        if self.ros_version != 2 or msgtype in self._from_builtin or msgtype not in self.builtin.fielddefs:
            return False
        self._stored_types.pop(msgtype, None)
        self._from_builtin.add(msgtype)
        self.store = self._build()
        self._deserialize = self.store.deserialize_cdr
        self._fast.clear()
        return True

    def validate(self, raw: bytes | memoryview, msgtype: str) -> Typestore:
        """Decode one real message (falling back if needed); the store that decodes `msgtype` then."""
        self.deserialize(raw, msgtype)
        return self.store


def _fast_decoder(store: Typestore, msgtype: str, ros_version: int) -> Callable[[bytes | memoryview], object]:
    """Typestore.deserialize_* without its per-call lookups and without copying the payload (a memoryview
    instead of `raw[4:]`); used once a type has decoded through the checked path, and any failure goes
    back to that path for its error message."""
    msgdef = store.get_msgdef(msgtype)
    cls = msgdef.cls
    if ros_version == 1:
        ros1 = msgdef.deserialize_ros1

        def decode_ros1(raw: bytes | memoryview) -> object:
            message, pos = ros1(raw, 0, cls, store)
            if pos != len(raw):
                raise ValueError(msgtype)
            return message

        return decode_ros1
    little, big = msgdef.deserialize_cdr_le, msgdef.deserialize_cdr_be

    def decode_cdr(raw: bytes | memoryview) -> object:
        view = memoryview(raw)
        if view[0] != 0 or view[1] > 1:
            raise ValueError(msgtype)
        message, pos = (little if view[1] else big)(view[4:], 0, cls, store)
        if pos + 7 < len(view):
            raise ValueError(msgtype)
        return message

    return decode_cdr


def _renamed(desc: object, moved: Mapping[str, str]) -> object:
    node, rest = desc  # type: ignore[misc]
    if node == Nodetype.NAME:
        return (node, moved.get(rest, rest))
    if node in (Nodetype.ARRAY, Nodetype.SEQUENCE) and rest[0][0] == Nodetype.NAME:
        return (node, ((Nodetype.NAME, moved.get(rest[0][1], rest[0][1])), rest[1]))
    return desc


def _split_srv(text: str) -> tuple[str, str]:
    lines = text.splitlines()
    for index, line in enumerate(lines):
        if line.strip() == "---":
            return "\n".join(lines[:index]) + "\n", "\n".join(lines[index + 1 :]) + "\n"
    return text, ""
