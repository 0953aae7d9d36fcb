"""ROS 1's one parameter server in the Graph protocol's per-node shape (`Parameters`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.ros1.master_client import RemoteError

if TYPE_CHECKING:
    from rostool.graph.base import ParameterDescriptor
    from rostool.graph.ros1.core import Ros1Core


class ServerParameters:
    """The parameter server in the per-node shape: NODE, when given, is a namespace (as rosparam takes it);
    names are the server's full names."""

    def __init__(self, graph: Ros1Core, node: str | None) -> None:
        self.master = graph.master
        self.resolve = graph.resolve
        self.node = graph.resolve(node or "/")

    def names(self) -> list[str]:
        ns = self.node
        return [n for n in sorted(self.master.param_names()) if ns in ("/", n) or n.startswith(ns + "/")]

    def value(self, name: str) -> Any:
        name = self.resolve(name)
        try:
            return self.master.get_param(name)
        except RemoteError as err:
            raise RostoolError(f"parameter {name} is not set") from err

    def show(self, name: str) -> tuple[Any, str]:
        from rostool.output.yaml_text import param_yaml

        value = self.value(name)
        return value, param_yaml(value)

    def set(self, name: str, value: Any) -> tuple[bool, str]:
        """Set like rosparam: a mapping updates the namespace key by key instead of replacing it."""
        if isinstance(value, dict):
            for key, item in value.items():
                self.set(key if str(key).startswith("/") else f"{name.rstrip('/')}/{key}", item)
            return True, ""
        try:
            self.master.set_param(self.resolve(name), value)
        except OverflowError as err:
            raise RostoolError(f"{name}: integers must fit in 32 bits on the ROS 1 parameter server") from err
        except TypeError as err:
            why = f"this value cannot be stored on the parameter server ({err})"
            raise RostoolError(f"{name}: {why}") from err
        return True, ""

    def delete(self, name: str) -> tuple[bool, str]:
        name = self.resolve(name)
        try:
            self.master.delete_param(name)
        except RemoteError as err:
            raise RostoolError(f"parameter {name} is not set, nothing to delete") from err
        return True, ""

    def descriptor(self, name: str) -> ParameterDescriptor:
        raise RostoolError("param describe applies to ROS 2 nodes (ROS 1 parameters have no descriptors)")

    def dump(self) -> Any:
        return self.value(self.node)

    def load(self, document: Any, use_wildcard: bool, source: str) -> list[tuple[str, bool, str]]:
        """The document under NODE (the namespace); a single value needs a namespace other than /."""
        if document is None:
            raise RostoolError(f"{source} holds no parameters")
        if not isinstance(document, dict) and self.node == "/":
            raise RostoolError(f"{source} holds a single value; give a NAMESPACE to store it under")
        self.set(self.node, document)
        return []
