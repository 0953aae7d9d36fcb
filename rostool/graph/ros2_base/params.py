"""ROS 2 parameters: each node serves them on `<node>/list_parameters`, `get_parameters`, `set_parameters`
and `describe_parameters` (rcl_interfaces services); values travel as rcl_interfaces/msg/ParameterValue.

Deleting is a set_parameters call with a NOT_SET value (as ros2param does); dump and load use the parameter
file layout of `ros2 param dump` and rcl: `/node: ros__parameters: {name: value}`, dotted names nested."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.graph.base import ParameterDescriptor
    from rostool.graph.ros2_base.transport import Ros2Host, ServiceClient

NOT_SET, BOOL, INTEGER, DOUBLE, STRING = 0, 1, 2, 3, 4
BYTE_ARRAY, BOOL_ARRAY, INTEGER_ARRAY, DOUBLE_ARRAY, STRING_ARRAY = 5, 6, 7, 8, 9
TYPE_NAMES = {
    NOT_SET: "not set", BOOL: "boolean", INTEGER: "integer", DOUBLE: "double", STRING: "string",
    BYTE_ARRAY: "byte array", BOOL_ARRAY: "boolean array", INTEGER_ARRAY: "integer array",
    DOUBLE_ARRAY: "double array", STRING_ARRAY: "string array",
}  # fmt: skip
_FIELDS = {
    BOOL: "bool_value", INTEGER: "integer_value", DOUBLE: "double_value", STRING: "string_value",
    BYTE_ARRAY: "byte_array_value", BOOL_ARRAY: "bool_array_value", INTEGER_ARRAY: "integer_array_value",
    DOUBLE_ARRAY: "double_array_value", STRING_ARRAY: "string_array_value",
}  # fmt: skip
VALUE_TYPE = "rcl_interfaces/msg/ParameterValue"
NODE_SETTLE_SECONDS = 3.0  # how long discovery may take to show the node's services


def to_python(value: Any) -> Any:
    """A ParameterValue message as a plain Python value (None when not set)."""
    field = _FIELDS.get(int(value.type))
    if field is None:
        return None
    found = getattr(value, field)
    return found.tolist() if hasattr(found, "tolist") else (list(found) if isinstance(found, list) else found)


def type_of(value: Any) -> int:
    if isinstance(value, bool):
        return BOOL
    if isinstance(value, int):
        return INTEGER
    if isinstance(value, float):
        return DOUBLE
    if isinstance(value, str):
        return STRING
    if isinstance(value, list) and value:
        if all(isinstance(v, bytes) and len(v) == 1 for v in value):  # a dump's `!!binary` items
            return BYTE_ARRAY
        if all(isinstance(v, bool) for v in value):
            return BOOL_ARRAY
        if all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            return INTEGER_ARRAY
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return DOUBLE_ARRAY
        if all(isinstance(v, str) for v in value):
            return STRING_ARRAY
    raise RostoolError(
        f"{value!r} cannot be a ROS 2 parameter: use a bool, integer, double, string "
        "or a non-empty list of one of them"
    )


def value_fields(value: Any) -> dict[str, Any]:
    """The fields of the ParameterValue holding `value`."""
    return typed_fields(type_of(value), value)


def typed_fields(kind: int, value: Any) -> dict[str, Any]:
    """The fields of a ParameterValue of a known type (an empty array, or NOT_SET, included)."""
    if kind == NOT_SET:
        return {"type": NOT_SET}
    item = [float(v) for v in value] if kind == DOUBLE_ARRAY else value
    if kind == BYTE_ARRAY:
        item = [v[0] if isinstance(v, bytes) else v for v in value]
    return {"type": kind, _FIELDS[kind]: item}


def from_python(store: Any, value: Any) -> Any:
    from rostool.interfaces.fill import build_message  # numpy: ~0.1 s of CPU that listings do not need

    return build_message(store, VALUE_TYPE, value_fields(value))


def describe_value(value: Any) -> str:
    """ros2 param get's sentence for a value."""
    kind = int(value.type)
    plain = to_python(value)
    if kind == NOT_SET:
        return "Parameter not set."
    label = TYPE_NAMES[kind].capitalize()
    if kind >= BYTE_ARRAY:
        return f"{label.replace(' array', '')} values are: {plain}"
    return f"{label} value is: {plain}"


class ParameterClient:
    """The parameter services of one node."""

    def __init__(self, graph: Ros2Host, node: str, timeout: float = 5.0) -> None:
        self.node = graph.resolve(node)
        self._graph = graph
        self._timeout = timeout
        self._clients: dict[str, ServiceClient] = {}

    def _call(self, verb: str, request: dict[str, Any]) -> Any:
        client = self._clients.get(verb)
        if client is None:
            if not self._clients:
                self._check_node()
            srv_type = "rcl_interfaces/srv/" + "".join(w.capitalize() for w in verb.split("_"))
            client = self._clients[verb] = self._graph.service_client(f"{self.node}/{verb}", srv_type)
        if not client.wait_for_server(self._timeout):
            raise RostoolError(
                f"node {self.node} does not serve {verb}: no server of {client.service} matched within "
                f"{self._timeout:g} s (see `rostool service list`)"
            )
        from rostool.interfaces.fill import build_message

        store = self._graph.types.store
        return client.call(build_message(store, client.request_type, request), self._timeout)

    def _check_node(self) -> None:
        """Fail at once, after discovery settles, when no participant serves any `<node>/...` service.
        Service endpoints come with discovery; the node names (ros_discovery_info) may come later."""
        graph = self._graph
        graph.before_node_check()
        deadline = time.monotonic() + NODE_SETTLE_SECONDS
        while True:
            if graph.serves_under(self.node + "/"):
                return
            if time.monotonic() >= deadline:
                break
            time.sleep(0.05)
        if graph.announces_node(self.node):
            raise RostoolError(f"node {self.node} serves no parameter services (it was started without them)")
        raise RostoolError(
            f"unknown node {self.node}: no ROS 2 participant serves its parameter services "
            "(see `rostool node list`)"
        )

    def names(self) -> list[str]:
        response = self._call("list_parameters", {"depth": 0})
        return sorted(response.result.names)

    def get(self, name: str) -> Any:
        return self.values([name])[0]

    def values(self, names: list[str]) -> list[Any]:
        """The ParameterValue of each name, in order (NOT_SET for the ones the node does not have)."""
        response = self._call("get_parameters", {"names": names})
        if not response.values and names:  # rclpy answers an undeclared name with no values at all
            raise RostoolError(f"parameter not set: node {self.node} has no parameter {', '.join(names)}")
        if len(response.values) != len(names):
            raise RostoolError(
                f"node {self.node} returned {len(response.values)} values for {len(names)} names"
            )
        return list(response.values)

    def set(self, name: str, value: Any) -> tuple[bool, str]:
        _, ok, reason = self.set_fields({name: value_fields(value)})[0]
        return ok, reason

    def delete(self, name: str) -> tuple[bool, str]:
        _, ok, reason = self.set_fields({name: typed_fields(NOT_SET, None)})[0]
        return ok, reason

    def set_fields(self, fields: dict[str, dict[str, Any]]) -> list[tuple[str, bool, str]]:
        """One set_parameters call; the node judges each parameter on its own: (name, successful, reason)."""
        parameters = [{"name": name, "value": value} for name, value in fields.items()]
        response = self._call("set_parameters", {"parameters": parameters})
        if len(response.results) != len(fields):
            raise RostoolError(
                f"node {self.node} returned {len(response.results)} results for {len(fields)} parameters"
            )
        return [
            (name, bool(r.successful), str(r.reason))
            for name, r in zip(fields, response.results, strict=True)
        ]

    def describe(self, name: str) -> Any:
        response = self._call("describe_parameters", {"names": [name]})
        if not response.descriptors:
            raise RostoolError(f"node {self.node} returned no description for {name}")
        return response.descriptors[0]


# --- parameter files ---------------------------------------------------------------------------------

SEPARATOR = "."
WILDCARD = "/**"
SECTION = "ros__parameters"


def dump_document(client: ParameterClient) -> dict[str, Any]:
    """Every parameter of the node as `ros2 param dump` lays it out."""
    names = client.names()
    values = client.values(names) if names else []
    flat = {name: _file_value(value) for name, value in zip(names, values, strict=True)}
    return {client.node: {SECTION: nest(flat)}}


def _file_value(value: Any) -> Any:
    """A value as ros2 param dump writes it: a byte array as rclpy's single bytes (YAML `!!binary`)."""
    plain = to_python(value)
    if int(value.type) == BYTE_ARRAY:
        return [bytes([b & 0xFF]) if isinstance(b, int) else bytes(b) for b in plain]
    return plain


def nest(flat: dict[str, Any]) -> dict[str, Any]:
    """`a.b: 1` becomes `a: {b: 1}`; a name whose prefix is itself a value stays dotted (it loads back the
    same)."""
    tree: dict[str, Any] = {}
    for name in sorted(flat):
        _insert(tree, name, flat[name])
    return tree


def _insert(tree: dict[str, Any], name: str, value: Any) -> None:
    head, separator, rest = name.partition(SEPARATOR)
    if separator and head and rest and isinstance(tree.setdefault(head, {}), dict):
        _insert(tree[head], rest, value)
    else:
        tree[name] = value


def flatten(tree: dict[Any, Any], prefix: str = "") -> dict[str, Any]:
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, name + SEPARATOR))
        else:
            flat[name] = value
    return flat


def file_parameters(document: Any, node: str, use_wildcard: bool, source: str) -> dict[str, Any]:
    """The parameters a file gives `node`: the `/**` section first (when used), then the node's own."""
    if not isinstance(document, dict):
        raise RostoolError(
            f"{source} is not a ROS 2 parameter file: expected `/node: {SECTION}: ...` mappings"
        )
    sections = [(WILDCARD, document[WILDCARD])] if use_wildcard and WILDCARD in document else []
    sections += _node_sections(document, node)
    parameters: dict[str, Any] = {}
    for key, section in sections:
        parameters.update(flatten(_parameters_of(section, key, source)))
    if not parameters:
        skipped = f" or {WILDCARD}" if use_wildcard else f" ({WILDCARD} is skipped with --no-use-wildcard)"
        keys = ", ".join(str(k) for k in document) or "none"
        raise RostoolError(
            f"{source} does not contain any valid parameters for {node}{skipped}; its keys: {keys}"
        )
    return parameters


def _node_sections(document: dict[Any, Any], node: str) -> list[tuple[str, Any]]:
    """rcl's ways to name a node: `/ns/node`, `ns/node`, or namespaces nested as keys (`/ns: node: ...`)."""
    parts = node.strip("/").split("/")
    found = []
    for cut in range(1, len(parts) + 1):
        for key in ("/" + "/".join(parts[:cut]), "/".join(parts[:cut])):
            section = document.get(key)
            for part in parts[cut:]:
                section = section.get(part) if isinstance(section, dict) else None
            if section is not None:
                found.append((key + "".join(f"/{p}" for p in parts[cut:]), section))
    return found


def _parameters_of(section: Any, key: str, source: str) -> dict[Any, Any]:
    if not isinstance(section, dict) or SECTION not in section:
        raise RostoolError(
            f"{source} is not a valid ROS parameter file for node {key}: expected `{key}: {SECTION}: "
            "NAME: VALUE`, as `rostool --ros2 param dump` writes"
        )
    parameters = section[SECTION] or {}
    if not isinstance(parameters, dict):
        raise RostoolError(f"{source}: {key}: {SECTION} must be a mapping of names to values")
    return parameters


def load_fields(
    client: ParameterClient, parameters: dict[str, Any], source: str
) -> dict[str, dict[str, Any]]:
    """ParameterValue fields for each file value. An empty list carries no type of its own, so it takes
    the array type the node has now (else boolean array, as rclpy picks)."""
    empty = [name for name, value in parameters.items() if value == []]
    current = dict(zip(empty, client.values(empty), strict=True)) if empty else {}
    fields: dict[str, dict[str, Any]] = {}
    for name, value in parameters.items():
        if name in current:
            kind = int(current[name].type)
            fields[name] = typed_fields(kind if kind >= BYTE_ARRAY else BOOL_ARRAY, [])
            continue
        try:
            fields[name] = value_fields(value)
        except RostoolError as err:
            raise RostoolError(f"{source}: parameter {name}: {err}") from err
    return fields


class NodeParameters(ParameterClient):
    """The Graph protocol's `Parameters` of one ROS 2 node."""

    def show(self, name: str) -> tuple[Any, str]:
        value = self.get(name)
        if int(value.type) == NOT_SET:
            raise RostoolError(f"parameter {name} is not set on node {self.node}")
        return to_python(value), describe_value(value)

    def descriptor(self, name: str) -> ParameterDescriptor:
        d = self.describe(name)
        return {"name": d.name, "type": TYPE_NAMES.get(int(d.type), str(d.type)),
                "description": d.description, "additional_constraints": d.additional_constraints,
                "read_only": bool(d.read_only)}  # fmt: skip

    def dump(self) -> Any:
        return dump_document(self)

    def load(self, document: Any, use_wildcard: bool, source: str) -> list[tuple[str, bool, str]]:
        parameters = file_parameters(document, self.node, use_wildcard, source)
        return self.set_fields(load_fields(self, parameters, source))
