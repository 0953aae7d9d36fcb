"""ROS 1 message types: the built-in Noetic store plus types learned from the wire.

A type is identified by (name, md5sum). Types the built-in store knows with the same md5 are used as
they are; any other type is parsed from the `message_definition` a publisher sends (or a bag stores)
into a store of its own, so two different definitions of one name never clash.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

import rostool.interfaces.rosbags_fix  # noqa: F401 - must run before types are registered
from rostool.errors import RostoolError
from rostool.interfaces.names import to_ros1_name, to_store_name

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore


@dataclass(frozen=True)
class Ros1Type:
    """Everything the wire needs to know about one message type."""

    name: str  # ROS 1 spelling, e.g. std_msgs/String
    md5sum: str
    definition: str
    store: Typestore

    @property
    def store_name(self) -> str:
        return to_store_name(self.name)

    def deserialize(self, payload: bytes | memoryview) -> Any:
        return self.store.deserialize_ros1(payload, self.store_name)

    def serialize(self, message: object) -> bytes:
        return bytes(self.store.serialize_ros1(message, self.store_name))

    def message_class(self) -> type:
        return self.store.types[self.store_name]


@lru_cache(maxsize=1)
def builtin_store() -> Typestore:
    return get_typestore(Stores.ROS1_NOETIC)


class TypeRegistry:
    """Resolves ROS 1 type names to `Ros1Type`s; thread-safe, caches what it learns."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._known: dict[tuple[str, str], Ros1Type] = {}

    def builtin(self, name: str) -> Ros1Type:
        """A type from the built-in store; RostoolError when unknown."""
        ros1_name = to_ros1_name(to_store_name(name))
        store = builtin_store()
        store_name = to_store_name(ros1_name)
        if store_name not in store.fielddefs:
            raise RostoolError(
                f"unknown message type {name!r}: not a built-in ROS 1 type "
                "(try `rostool msg list`, or check the spelling pkg/Type)"
            )
        definition, md5sum = store.generate_msgdef(store_name)
        found = Ros1Type(ros1_name, md5sum, definition, store)
        with self._lock:
            self._known.setdefault((ros1_name, md5sum), found)
        return found

    def has_builtin(self, name: str) -> bool:
        return to_store_name(name) in builtin_store().fielddefs

    def resolve(self, name: str, md5sum: str, definition: str | None) -> Ros1Type:
        """The type a peer announced: built-in when the md5 matches, else parsed from its definition."""
        key = (name, md5sum)
        with self._lock:
            cached = self._known.get(key)
        if cached is not None:
            return cached
        if self.has_builtin(name):
            candidate = self.builtin(name)
            if md5sum in ("*", candidate.md5sum):
                return candidate
        if not definition:
            raise RostoolError(
                f"cannot decode type {name} (md5 {md5sum}): it is not built in and the peer sent no "
                "message definition"
            )
        found = self._from_definition(name, definition)
        if md5sum not in ("*", found.md5sum):
            raise RostoolError(
                f"the definition of {name} the peer sent hashes to {found.md5sum}, not {md5sum}"
            )
        with self._lock:
            self._known[key] = found
        return found

    def from_header(self, header: Mapping[str, str]) -> Ros1Type:
        """The type a TCPROS connection header announces (its type, md5sum and message definition)."""
        definition = header.get("message_definition")
        return self.resolve(header.get("type", "*"), header.get("md5sum", "*"), definition)

    @staticmethod
    def _from_definition(name: str, definition: str) -> Ros1Type:
        store = get_typestore(Stores.EMPTY)
        try:
            store.register(get_types_from_msg(definition, to_store_name(name)))
            _text, md5sum = store.generate_msgdef(to_store_name(name))
        except Exception as err:  # rosbags raises several kinds for bad definitions
            raise RostoolError(f"cannot parse the message definition of {name}: {err}") from err
        return Ros1Type(name, md5sum, definition, store)
