"""`bag play` into a ROS 2 graph: ROS 2 bags' CDR bytes are written to DDS as stored.

The schedule, keys and status line are `play.Player`'s; only advertising differs. Each topic gets a DDS
writer with the bag's type name (definitions a bag brings are registered first, so types outside the
distro store play too) and transient_local durability where the recording publisher offered it. ROS 1
bags are not converted to ROS 2 (their topics are skipped), and --clock is a ROS 1 option here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

from rosbags.interfaces import ConnectionExtRosbag2

from rostool.bag.play import Console, Player, PlayOptions, _Plan
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from collections.abc import Callable

    from rostool.bag.reader import BagReader
    from rostool.graph.ros2.graph import Ros2Graph


class Ros2Player(Player):
    def __init__(
        self,
        reader: BagReader,
        graph: Ros2Graph,
        options: PlayOptions,
        console: Console | None = None,
        warn: Callable[[str], None] | None = None,
    ) -> None:
        if options.clock:
            raise RostoolError("--clock applies to ROS 1 graphs only in this rostool version")
        # Player only touches the graph in advertise(), which this class replaces.
        super().__init__(reader, cast(Any, graph), options, console, warn)
        self.ros2 = graph

    def advertise(self) -> None:
        """One DDS writer per topic; ROS 1 bags' topics are skipped."""
        playable = [c for c in self.connections if isinstance(c.ext, ConnectionExtRosbag2)]
        for conn in self.connections:
            if conn not in playable:
                self._skip(conn.topic, "ROS 1 bags play into ROS 1 graphs only", warn=False)
        if not playable:
            raise RostoolError(
                "nothing to play in ROS 2: no ROS 2 bag topics selected (ROS 1 bags play into ROS 1 graphs "
                "only: use --ros1)"
            )
        bag_types = self.reader.resolver.store.fielddefs
        self.ros2.types.register(bag_types)  # only the types the distro store lacks are added
        for conn in playable:
            topic = self.options.remap.get(conn.topic, conn.topic)
            existing = self._publishers.get(topic)
            if existing is not None:
                publisher, type_name = existing
                if type_name != conn.msgtype:
                    self._skip(conn.topic, f"a second type {conn.msgtype} on {topic}")
                    continue
            else:
                ext = cast(ConnectionExtRosbag2, conn.ext)
                latch = any(q.durability.value == 1 for q in ext.offered_qos_profiles)
                publisher = self.ros2.publisher(topic, conn.msgtype, latch)
                self._publishers[topic] = (publisher, conn.msgtype)
            self._plans[id(conn)] = _Plan(topic, publisher, None)
        for topic, why in self.result.skipped.items():
            self.warn(f"skipping {topic}: {why}")
