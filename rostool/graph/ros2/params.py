"""ROS 2 parameters: each node serves them on `<node>/list_parameters`, `get_parameters`, `set_parameters`
and `describe_parameters` (rcl_interfaces services); values travel as rcl_interfaces/msg/ParameterValue."""

from __future__ import annotations

from typing import Any

from rostool.errors import RostoolError
from rostool.interfaces.fill import build_message

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
    kind = type_of(value)
    item = [float(v) for v in value] if kind == DOUBLE_ARRAY else value
    return {"type": kind, _FIELDS[kind]: item}


def from_python(store: Any, value: Any) -> Any:
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

    def __init__(self, graph: Any, node: str, timeout: float = 5.0) -> None:
        self.node = graph.resolve(node)
        self._graph = graph
        self._timeout = timeout
        self._clients: dict[str, Any] = {}

    def _call(self, verb: str, request: dict[str, Any]) -> Any:
        from rostool.graph.ros2.services import ServiceClient

        client = self._clients.get(verb)
        if not self._clients and self.node not in self._graph.node_names():
            raise RostoolError(f"unknown node {self.node}: no ROS 2 participant announces it")
        if client is None:
            srv_type = "rcl_interfaces/srv/" + "".join(w.capitalize() for w in verb.split("_"))
            client = self._clients[verb] = ServiceClient(self._graph.session, f"{self.node}/{verb}", srv_type)
        if not client.wait_for_server(self._timeout):
            raise RostoolError(
                f"node {self.node} does not serve {verb} (no such node, or it runs without parameter "
                "services; see `rostool node list`)"
            )
        store = self._graph.types.store
        return client.call(build_message(store, client.request_type, request), self._timeout)

    def names(self) -> list[str]:
        response = self._call("list_parameters", {"depth": 0})
        return sorted(response.result.names)

    def get(self, name: str) -> Any:
        response = self._call("get_parameters", {"names": [name]})
        if not response.values:
            raise RostoolError(f"node {self.node} returned no value for {name}")
        return response.values[0]

    def set(self, name: str, value: Any) -> tuple[bool, str]:
        parameter = {"name": name, "value": value_fields(value)}
        response = self._call("set_parameters", {"parameters": [parameter]})
        result = response.results[0]
        return bool(result.successful), str(result.reason)

    def describe(self, name: str) -> Any:
        response = self._call("describe_parameters", {"names": [name]})
        if not response.descriptors:
            raise RostoolError(f"node {self.node} returned no description for {name}")
        return response.descriptors[0]
