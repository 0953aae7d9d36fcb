"""`bag play` into a ROS 2 graph: every message is written to DDS as CDR bytes with a ROS 2 type name.

The schedule, keys and status line are `play.Player`'s; only advertising and the bytes differ. Each topic
gets a DDS writer, transient_local where the recording publisher latched (ROS 1) or offered it (ROS 2).

- ROS 2 bags: the stored CDR bytes as they are, with the bag's type name (definitions a bag brings are
  registered first, so types outside the distro store play too).
- ROS 1 bags: converted as `bag convert` does (rosbags' `ros1_to_cdr`, its static renames such as
  tf/tfMessage -> tf2_msgs/msg/TFMessage, ROS 2's std_msgs/Header without `seq`). Types the distro store
  lacks (rosgraph_msgs/Log, turtlesim/...) are registered as converted. The first message of a topic is
  decoded with the graph's type; a type laid out differently in ROS 2 is skipped with a warning.
- --clock publishes rosgraph_msgs/msg/Clock on /clock at --hz, as `ros2 bag play --clock HZ` does: the
  playback clock's time, not each message's stamp. The writer is reliable, which best-effort readers
  (rclcpp's ClockQoS) match too.
- rosbag2's control services (`/rosbag2_player/pause`, `set_rate`, `seek`, ...: player_services.py) are
  served while playing; they act as the keys do.
"""

from __future__ import annotations

import struct
from functools import cached_property, partial
from typing import TYPE_CHECKING, Any, cast

from rosbags.interfaces import Connection, ConnectionExtRosbag1, ConnectionExtRosbag2

from rostool.bag.crossver import CrossVersionStores
from rostool.bag.failures import describe
from rostool.bag.play import Player, RawPublisher, _Kind
from rostool.bag.player_services import Controls, Served, serve_player
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from collections.abc import Callable

    from rosbags.typesys.store import Typestore


# Little-endian CDR encapsulation, then builtin_interfaces/Time (int32 sec, uint32 nanosec).
_CDR_CLOCK = struct.Struct("<4siI")
_CDR_LE = b"\x00\x01\x00\x00"


class Ros2Player(Player):
    graph_name = "ROS 2"
    clock_per_message = False  # rosbag2 publishes /clock at its frequency only

    @cached_property
    def _cdr_stores(self) -> CrossVersionStores:
        """The bag's ROS 1 types as ROS 2 types, made as they are first played."""
        return CrossVersionStores(dst_version=2)

    served: Served | None = None  # rosbag2's control services, once advertised

    def advertise(self) -> None:
        if self.reader.ros_version == 2:
            self.types.register(self.reader.resolver.store.fielddefs)  # only what the distro lacks
        super().advertise()
        if self._plans:
            self.controls = Controls()
            self.served = serve_player(self.graph, self.controls, self.warn)

    @property
    def serves_controls(self) -> bool:
        return bool(self.served)

    def close_controls(self) -> None:
        super().close_controls()
        if self.served is not None:
            self.served.close()

    def _kind_of(self, conn: Connection) -> _Kind:
        """One DDS writer per topic; ROS 1 messages are converted, the first one checked."""
        type_name, convert, latch = self._ros2_type_of(conn)
        return _Kind(
            key=type_name,
            label=type_name,
            advertise=lambda topic: self.graph.raw_publisher(topic, type_name, latch),
            convert=convert,
            verify=None if convert is None else partial(self.types.deserialize, store_name=type_name),
        )

    def _ros2_type_of(self, conn: Connection) -> tuple[str, Callable[[Any], Any] | None, bool]:
        """(ROS 2 type name, ROS 1 -> CDR conversion or None, latched) of a bag connection."""
        if isinstance(conn.ext, ConnectionExtRosbag2):
            latch = any(q.durability.value == 1 for q in conn.ext.offered_qos_profiles)
            return conn.msgtype, None, latch
        from rosbags.convert.converter import STATIC_MSGTYPE_RENAMES

        ext = cast(ConnectionExtRosbag1, conn.ext)
        type_name = STATIC_MSGTYPE_RENAMES.get(conn.msgtype, conn.msgtype)
        store = self._converted_store(conn.msgtype, type_name)
        return type_name, partial(store.ros1_to_cdr, typename=type_name), bool(ext.latching)

    def _converted_store(self, ros1_type: str, type_name: str) -> Typestore:
        """The bag's ROS 1 types as ROS 2 types (as `bag convert` makes them), registered with the graph."""
        resolver = self.reader.resolver
        if ros1_type in resolver.unknown:
            raise RostoolError(resolver.missing_message(ros1_type))
        try:
            store = self._cdr_stores.store_for(resolver.store, ros1_type, type_name)
            self.types.register(store.fielddefs)  # only the types the distro store lacks
        except Exception as err:  # a definition rosbags cannot express in ROS 2
            raise RostoolError(f"{ros1_type} cannot be converted to ROS 2: {describe(err)}") from err
        return store

    def _advertise_clock(self) -> RawPublisher:
        return self.graph.raw_publisher("/clock", "rosgraph_msgs/msg/Clock")

    def _clock_message(self, stamp: int) -> bytes:
        return _CDR_CLOCK.pack(_CDR_LE, *divmod(stamp, 1_000_000_000))
