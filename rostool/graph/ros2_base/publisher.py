"""A ROS 2 publisher over a transport's writer: messages go out as rosbags' CDR bytes."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rostool.graph.ros2_base.transport import Writer
    from rostool.interfaces.ros2_types import Ros2Types


MATCH_POLL = 0.005  # seconds between looks at the matched count (a status read: microseconds)


class Ros2Publisher:
    def __init__(self, topic: str, store_name: str, writer: Writer, types: Ros2Types) -> None:
        self.topic = topic
        self.type_name = store_name
        self._writer = writer
        self._types = types

    def publish(self, message: object) -> None:
        self.publish_raw(self._types.serialize(message, self.type_name))

    def publish_raw(self, payload: bytes) -> None:
        """Write CDR bytes (with their 4-byte encapsulation header) as they are."""
        self._writer.write(payload)

    def wait_for_subscribers(self, count: int, timeout: float) -> bool:
        """Until `count` subscriptions matched this writer (the transport's matched count), at most
        `timeout` s."""
        deadline = time.monotonic() + timeout
        while self.subscriber_count < count:
            if time.monotonic() >= deadline:
                return False
            time.sleep(MATCH_POLL)
        return True

    @property
    def subscriber_count(self) -> int:
        return self._writer.matched()
