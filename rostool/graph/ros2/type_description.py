"""Message types from the publisher's node: REP 2016 type descriptions, as Jazzy's nodes serve them.

Every rclcpp/rclpy node of Iron and later serves `<node>/get_type_description`
(type_description_interfaces/srv/GetTypeDescription): given a type name and its RIHS01 hash, it answers
with the type's TypeDescription (its fields, and every type it references, recursively, sorted by name).
rostool does the same for the types its publishers use (`TypeDescriptionServer`, started with the first
publisher), and, when a subscription meets a type it does not know, asks the publisher's node for it
(`fetch_types`) and converts the description into rosbags field definitions.

rosbags computes the RIHS01 hash independently from those definitions; the conversion is accepted only when
that hash equals the one the publisher announces in its endpoint USER_DATA (`typehash=RIHS01_...;`), which
proves every field type, capacity and nested name mapped exactly. Field default values are ignored (echo
and record do not need them) and constants are not part of a type description (REP 2016), so types
learned this way have none.
"""

from __future__ import annotations

import keyword
import re
import time
from collections.abc import Iterable, Mapping
from typing import Any

from rosbags.interfaces import Nodetype

import rostool.interfaces.rosbags_fix  # noqa: F401 - must run before types are registered
from rostool.graph.ros2.types import TypeSupport

SRV_TYPE = "type_description_interfaces/srv/GetTypeDescription"
RESPONSE_TYPE = SRV_TYPE + "_Response"
DESCRIPTION_MSG = "type_description_interfaces/msg/TypeDescription"
SERVICE_NAME = "get_type_description"
CALL_TIMEOUT = 3.0  # a node that serves descriptions answers in well under a second
ANNOUNCE_WAIT = 1.0  # how long to wait for the node's service to show up in discovery
EMPTY_MEMBER = "structure_needs_at_least_one_member"

# type_description_interfaces/msg/FieldType: ids 1-48 are single values, +48 fixed arrays, +96 bounded
# sequences, +144 unbounded sequences. 0 is "not set".
NESTED = 1
BOUNDED_STRING = 21
BOUNDED_WSTRING = 22
ARRAY_OFFSET, BOUNDED_SEQUENCE_OFFSET, SEQUENCE_OFFSET = 48, 96, 144
_PRIMITIVE_IDS: dict[str, int] = {
    "int8": 2, "uint8": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7, "int64": 8, "uint64": 9,
    "float32": 10, "float64": 11, "float128": 12, "char": 13, "wchar": 14, "bool": 15, "byte": 16,
    "string": 17, "wstring": 18,
}  # fmt: skip
_PRIMITIVE_NAMES = {number: name for name, number in _PRIMITIVE_IDS.items()}
_PRIMITIVE_ALIASES = {"octet": "byte"}  # rosbags' IDL reader may name ROS `byte` by its IDL name
# rosbags can neither hash nor (de)serialize these, so a description using them is refused up front.
_UNSUPPORTED_IDS = {
    14: "wchar", 18: "wstring", 19: "fixed string", 20: "fixed wstring", 22: "bounded wstring",
}  # fmt: skip

_IDENTIFIER = r"[A-Za-z][A-Za-z0-9_]*"
_TYPE_NAME = re.compile(rf"{_IDENTIFIER}/{_IDENTIFIER}/{_IDENTIFIER}")
_FIELD_NAME = re.compile(_IDENTIFIER)

Typesdict = dict[str, tuple[list[Any], list[tuple[str, Any]]]]


class DescriptionError(ValueError):
    """A type description rostool cannot use; the text says why."""


def available(types: TypeSupport) -> bool:
    """Type descriptions exist from Iron on: distros whose nodes announce type hashes."""
    return DESCRIPTION_MSG in types.store.fielddefs and types.type_hash(DESCRIPTION_MSG) is not None


def service_of(node: str) -> str:
    return node.rstrip("/") + "/" + SERVICE_NAME


# --- rosbags field definitions -> TypeDescription -------------------------------------------------------


def describe(fielddefs: Mapping[str, Any], type_name: str) -> dict[str, Any]:
    """The TypeDescription of `type_name` (nested dicts, as the message has them), referenced types sorted
    by name as REP 2016 orders them."""
    individual: dict[str, dict[str, Any]] = {}
    pending = [type_name]
    while pending:
        name = pending.pop()
        if name in individual:
            continue
        if name not in fielddefs:
            raise DescriptionError(f"type {name} is not known here")
        fields = [_describe_field(field, desc) for field, desc in fielddefs[name][1]]
        if not fields:  # rosidl gives empty messages one placeholder member
            fields = [_describe_field(EMPTY_MEMBER, (Nodetype.BASE, ("uint8", 0)))]
        individual[name] = {"type_name": name, "fields": fields}
        pending.extend(f["type"]["nested_type_name"] for f in fields if f["type"]["nested_type_name"])
    referenced = [individual[name] for name in sorted(individual) if name != type_name]
    return {"type_description": individual[type_name], "referenced_type_descriptions": referenced}


def _describe_field(name: str, desc: Any) -> dict[str, Any]:
    kind, args = desc
    offset, capacity = 0, 0
    if kind == Nodetype.ARRAY:
        desc, capacity = args
        offset = ARRAY_OFFSET
    elif kind == Nodetype.SEQUENCE:
        desc, capacity = args
        offset = BOUNDED_SEQUENCE_OFFSET if capacity else SEQUENCE_OFFSET
    element_kind, element = desc
    string_capacity, nested = 0, ""
    if element_kind == Nodetype.NAME:
        type_id, nested = NESTED, element
    else:
        primitive, bound = element
        primitive = _PRIMITIVE_ALIASES.get(primitive, primitive)
        if primitive not in _PRIMITIVE_IDS:
            raise DescriptionError(f"field {name} has type {primitive}, which has no type description id")
        type_id = _PRIMITIVE_IDS[primitive]
        if bound and primitive in ("string", "wstring"):
            type_id = BOUNDED_STRING if primitive == "string" else BOUNDED_WSTRING
            string_capacity = bound
    field_type = {
        "type_id": offset + type_id, "capacity": capacity, "string_capacity": string_capacity,
        "nested_type_name": nested,
    }  # fmt: skip
    return {"name": name, "type": field_type, "default_value": ""}


# --- TypeDescription -> rosbags field definitions -------------------------------------------------------


def as_dict(message: Any) -> dict[str, Any]:
    """A received TypeDescription message as the nested dicts `describe` makes."""

    def individual(item: Any) -> dict[str, Any]:
        fields = [
            {"name": f.name, "type": {
                "type_id": int(f.type.type_id), "capacity": int(f.type.capacity),
                "string_capacity": int(f.type.string_capacity), "nested_type_name": f.type.nested_type_name,
            }, "default_value": f.default_value}
            for f in item.fields
        ]  # fmt: skip
        return {"type_name": item.type_name, "fields": fields}

    return {
        "type_description": individual(message.type_description),
        "referenced_type_descriptions": [individual(item) for item in message.referenced_type_descriptions],
    }


def to_fielddefs(description: Mapping[str, Any]) -> Typesdict:
    """rosbags' `{type name: ([], fields)}` for the described type and every type it references."""
    typs: Typesdict = {}
    for item in [description["type_description"], *description["referenced_type_descriptions"]]:
        name = item["type_name"]
        if not _TYPE_NAME.fullmatch(name):
            raise DescriptionError(f"{name!r} is not a pkg/msg/Name type name")
        if name in typs:
            raise DescriptionError(f"type {name} is described twice")
        typs[name] = ([], [_field_def(name, field) for field in item["fields"]])
    missing = sorted(_nested_names(typs) - typs.keys())
    if missing:
        raise DescriptionError(f"the description lacks the referenced type(s) {', '.join(missing)}")
    return typs


def _field_def(type_name: str, field: Mapping[str, Any]) -> tuple[str, Any]:
    name = field["name"]
    if not _FIELD_NAME.fullmatch(name) or keyword.iskeyword(name):
        raise DescriptionError(f"{type_name} has a field named {name!r}, which is not a valid field name")
    field_type = field["type"]
    type_id, capacity = field_type["type_id"], field_type["capacity"]
    base_id = (type_id - 1) % ARRAY_OFFSET + 1
    element = _element(type_name, name, base_id, field_type)
    if type_id <= ARRAY_OFFSET:
        return name, element
    if type_id <= BOUNDED_SEQUENCE_OFFSET:
        return name, (Nodetype.ARRAY, (element, capacity))
    if type_id <= SEQUENCE_OFFSET:
        return name, (Nodetype.SEQUENCE, (element, capacity))
    if type_id <= SEQUENCE_OFFSET + ARRAY_OFFSET:
        return name, (Nodetype.SEQUENCE, (element, 0))
    raise DescriptionError(f"{type_name}.{name} has the unknown field type id {type_id}")


def _element(type_name: str, name: str, base_id: int, field_type: Mapping[str, Any]) -> Any:
    where = f"{type_name}.{name}"
    if base_id == NESTED:
        nested = field_type["nested_type_name"]
        if not _TYPE_NAME.fullmatch(nested):
            raise DescriptionError(f"{where} names the type {nested!r}, not a pkg/msg/Name type name")
        return (Nodetype.NAME, nested)
    if base_id in _UNSUPPORTED_IDS:
        raise DescriptionError(f"{where} is a {_UNSUPPORTED_IDS[base_id]}, which rostool cannot decode")
    if base_id == BOUNDED_STRING:
        return (Nodetype.BASE, ("string", field_type["string_capacity"]))
    if base_id not in _PRIMITIVE_NAMES:
        raise DescriptionError(f"{where} has the unknown field type id {field_type['type_id']}")
    return (Nodetype.BASE, (_PRIMITIVE_NAMES[base_id], 0))


def _nested_names(typs: Typesdict) -> set[str]:
    found: set[str] = set()
    for _consts, fields in typs.values():
        for _name, desc in fields:
            kind, args = desc
            element_kind, element = args[0] if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) else desc
            if element_kind == Nodetype.NAME:
                found.add(element)
    return found


def verified(typs: Typesdict, type_name: str, type_hash: str, store: Any) -> Typesdict:
    """The definitions when rosbags hashes them to `type_hash`, checked in a scratch store; every described
    type the session's `store` already knows must hash the same there (else it would decode differently).
    Returns the definitions the store lacks."""
    from rosbags.typesys import Stores, get_typestore

    scratch = get_typestore(Stores.EMPTY)
    try:
        scratch.register(typs)
        computed = scratch.hash_rihs01(type_name)
    except Exception as err:  # rosbags raises several kinds for definitions it cannot take
        raise DescriptionError(f"rosbags cannot use the described {type_name}: {err}") from err
    if computed != type_hash:
        raise DescriptionError(
            f"the description of {type_name} hashes to {computed}, not to the announced {type_hash}"
        )
    for name in sorted(typs.keys() & store.fielddefs.keys()):
        if store.hash_rihs01(name) != scratch.hash_rihs01(name):
            raise DescriptionError(f"the publisher's {name} differs from the one in rostool's type store")
    return {name: typ for name, typ in typs.items() if name not in store.fielddefs}


# --- the service ------------------------------------------------------------------------------------------


class TypeDescriptionServer:
    """Serves `<node>/get_type_description` for the types of this session's topics."""

    def __init__(self, session: Any, node: str) -> None:
        from rostool.graph.ros2.services import ServiceServer

        self._session = session
        self._types: TypeSupport = session.types
        self.service = service_of(node)
        self._server = ServiceServer(session, self.service, SRV_TYPE, self.answer)

    def answer(self, request: Any) -> Any:
        from rostool.interfaces.fill import build_message

        try:
            fields = self.response(request.type_name, request.type_hash)
        except Exception as err:  # never let one bad request stop the serving thread
            fields = {"successful": False, "failure_reason": f"cannot describe {request.type_name}: {err}"}
        return build_message(self._types.store, RESPONSE_TYPE, fields)

    def response(self, type_name: str, type_hash: str) -> dict[str, Any]:
        """The response fields: successful with the description, or a failure reason."""
        if type_name not in self._session.used_types():
            return {"successful": False, "failure_reason": f"type {type_name} is not used by this node"}
        own_hash = self._types.type_hash(type_name)
        if type_hash and type_hash != own_hash:
            reason = f"this node uses {type_name} with type hash {own_hash}, not {type_hash}"
            return {"successful": False, "failure_reason": reason}
        return {"successful": True, "type_description": self.describe(type_name)}

    def describe(self, type_name: str) -> dict[str, Any]:
        return describe(self._types.store.fielddefs, type_name)

    def close(self) -> None:
        self._server.close()


def fetch_types(
    session: Any, type_name: str, publishers: Iterable[tuple[str, str]], timeout: float = CALL_TIMEOUT
) -> str | None:
    """Ask the publishers' nodes ((node, announced hash) pairs) for `type_name` and register it in the
    session's types. Returns None when it is known now, else why not (for the unknown-type error)."""
    reasons: list[str] = []
    deadline = time.monotonic() + timeout
    for node, type_hash in dict.fromkeys(publishers):
        if not type_hash:
            reasons.append(f"{node} announces no type hash (a ROS 2 distro before Iron)")
            continue
        try:
            _fetch_from(session, node, type_name, type_hash, max(0.5, deadline - time.monotonic()))
            return None
        except DescriptionError as err:
            reasons.append(f"{node}: {err}")
    return "; ".join(reasons) or "no publisher's node is known"


def _fetch_from(session: Any, node: str, type_name: str, type_hash: str, timeout: float) -> None:
    from rostool.errors import RostoolError
    from rostool.graph.ros2.services import ServiceClient

    types: TypeSupport = session.types
    service = service_of(node)
    if not _announced(session, service, min(ANNOUNCE_WAIT, timeout)):
        raise DescriptionError(f"the node does not serve {service}")
    client = ServiceClient(session, service, SRV_TYPE)
    try:
        request = types.store.types[SRV_TYPE + "_Request"](type_name, type_hash, False)
        response = client.call(request, timeout)
    except RostoolError as err:
        raise DescriptionError(str(err)) from err
    finally:
        client.close()
    if not response.successful:
        raise DescriptionError(f"{service} refused: {response.failure_reason}")
    description = as_dict(response.type_description)
    described = description["type_description"]["type_name"]
    if described != type_name:
        raise DescriptionError(f"{service} described {described} instead of {type_name}")
    types.register(verified(to_fielddefs(description), type_name, type_hash, types.store))
    if types.store.hash_rihs01(type_name) != type_hash:  # as registered, the store must agree too
        raise DescriptionError(f"the registered {type_name} does not hash to {type_hash}")


def _announced(session: Any, service: str, timeout: float) -> bool:
    """Does discovery show a server of `service`? Its request reader may come a moment after the writer."""
    from rostool.graph.ros2_base.names import request_topic

    wanted = request_topic(service)
    deadline = time.monotonic() + timeout
    while True:
        cache = session.cache
        cache.poll()
        if any(e.dds_topic == wanted and not e.is_writer for e in cache.remote_endpoints()):
            return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.05)
