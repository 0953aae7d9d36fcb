"""Type stores for moving messages between ROS 1 and ROS 2 serializations.

ROS 1 and ROS 2 share message layouts except std_msgs/Header (ROS 1 has `seq`). rosbags converts the bytes
(`ros1_to_cdr` / `cdr_to_ros1`) but leaves building the destination store to its own converter, which is not
a public API; this builds the same store: the source's definitions with the other side's Header.
"""

from __future__ import annotations

from rosbags.typesys.store import Typestore


class CrossVersionStores:
    """One destination store per source store, learning each converted type on first use."""

    def __init__(self, dst_version: int) -> None:
        self.dst_version = dst_version
        self._stores: dict[int, Typestore] = {}

    def store_for(self, src: Typestore, src_msgtype: str, dst_msgtype: str) -> Typestore:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        store = self._stores.get(id(src))
        if store is None:
            other = Stores.ROS2_FOXY if self.dst_version == 2 else Stores.ROS1_NOETIC
            header = get_typestore(other).fielddefs["std_msgs/msg/Header"]
            store = get_typestore(Stores.EMPTY)
            store.register({**src.fielddefs, "std_msgs/msg/Header": header})
            self._stores[id(src)] = store
        if dst_msgtype not in store.fielddefs:
            text = src.generate_msgdef(src_msgtype, ros_version=self.dst_version)[0]
            typs = get_types_from_msg(text, dst_msgtype)
            typs.pop("std_msgs/msg/Header", None)
            store.register(typs)
        return store
