"""Type stores for moving messages between ROS 1 and ROS 2 serializations.

ROS 1 and ROS 2 share message layouts except std_msgs/Header (ROS 1 has `seq`). rosbags converts the bytes
(`ros1_to_cdr` / `cdr_to_ros1`) but leaves building the destination store to its own converter, which is not
a public API; this builds the same store: the source's definitions with the other side's Header.
"""

from __future__ import annotations

from typing import Any

from rosbags.typesys.store import Typestore


class CrossVersionStores:
    """One destination store per source store, learning each converted type on first use."""

    def __init__(self, dst_version: int) -> None:
        self.dst_version = dst_version
        self._stores: dict[int, tuple[Typestore, dict[str, Any]]] = {}

    def store_for(self, src: Typestore, src_msgtype: str, dst_msgtype: str) -> Typestore:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        known = self._stores.get(id(src))
        if known is None:
            header = get_types_from_msg(_HEADER_FIELDS[self.dst_version], HEADER)[HEADER]
            known = self._stores[id(src)] = (get_typestore(Stores.EMPTY), {**src.fielddefs, HEADER: header})
        store, fielddefs = known
        if dst_msgtype not in store.fielddefs:
            # Only the types this one uses: registering a whole source store (a distro's hundreds of
            # types) costs rosbags a generated class each, seconds on a loaded machine, and the first
            # message of a recording waits for it.
            wanted = _uses(fielddefs, src_msgtype)
            store.register({name: fielddefs[name] for name in wanted if name not in store.fielddefs})
        if dst_msgtype not in store.fielddefs:  # a renamed type (tf/tfMessage -> tf2_msgs/msg/TFMessage)
            text = src.generate_msgdef(src_msgtype, ros_version=self.dst_version)[0]
            typs = get_types_from_msg(text, dst_msgtype)
            typs.pop(HEADER, None)  # the other version's, registered with the types that use it
            store.register({name: typ for name, typ in typs.items() if name not in store.fielddefs})
        return store


HEADER = "std_msgs/msg/Header"
# The one type whose layout differs between the versions, as each defines it. Written out because reading
# it from rosbags' store of a distro imports that store's module (hundreds of classes, 0.2 s).
_HEADER_FIELDS = {
    1: "uint32 seq\nbuiltin_interfaces/Time stamp\nstring frame_id\n",
    2: "builtin_interfaces/Time stamp\nstring frame_id\n",
}


def _uses(fielddefs: dict[str, Any], msgtype: str) -> list[str]:
    """`msgtype` and every type its fields use, at any depth, by rosbags' field definitions."""
    from rosbags.interfaces import Nodetype

    found: list[str] = []
    todo = [msgtype]
    while todo:
        name = todo.pop()
        if name in found or name not in fielddefs:
            continue
        found.append(name)
        for _field, (kind, detail) in fielddefs[name][1]:
            if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
                kind, detail = detail[0]
            if kind == Nodetype.NAME:
                todo.append(detail)
    return found
