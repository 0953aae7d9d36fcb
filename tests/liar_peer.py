"""A misbehaving ROS 2 participant (rostool's own DDS, loopback): its ros_discovery_info samples are garbage
in turn (not CDR, counts of four billion, strings without end, names past any bound), and it writes on a topic
whose name and type are not ROS's. Prints "ready" once it has started lying; runs until killed."""

import struct
import time
from dataclasses import dataclass

from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]
from cyclonedds.core import Qos
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int32
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic

from rostool.graph.ros2.graph import Ros2Graph

HEADER = b"\x00\x01\x00\x00"
GID = bytes(range(16))
LIES = [
    b"garbage",
    HEADER + b"\xff" * 64,
    HEADER + GID + struct.pack("<I", 0xFFFFFFFF),  # four billion nodes
    HEADER + GID + struct.pack("<II", 1, 5000) + b"a" * 100,  # a string longer than the sample
    HEADER + GID + struct.pack("<II", 1, 3) + b"abc",  # a string without its terminator
    HEADER
    + GID
    + struct.pack("<II", 1, 2)
    + b"/\x00\x00\x00"
    + struct.pack("<I", 4000)
    + b"n" * 3999
    + b"\x00"
    + struct.pack("<I", 0xFFFFFFFF),  # a node whose gid count is four billion
]


@dataclass
class NotRos(IdlStruct, typename="no::such::Type_"):  # type: ignore[call-arg]
    x: int32


def main() -> None:
    graph = Ros2Graph("liar")
    session = graph.session
    odd = DataWriter(session.participant.dp, Topic(session.participant.dp, "zz_not_ros", NotRos), qos=Qos())
    print("ready", flush=True)
    while True:
        for lie in LIES:
            ddspy_write(session._info_writer._ref, lie)
            odd.write(NotRos(x=1))
            time.sleep(0.05)


if __name__ == "__main__":
    main()
