"""bag record from real rclpy publishers and bag play into a real rclpy subscriber (Jazzy and Kilted on
Fast DDS), on both ROS 2 backends (rostool's DDS, and rclpy in the peer venv), plus topic delay on a real
stamped publisher.

Referees: the real node (what it published, what it heard), rosbags' reader and Foxglove's
mcap-ros2-support decoder for the recorded files.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from tests.ros2_peers import RclpyPeer
from tests.support import TESTDATA, Watched, rostool

if TYPE_CHECKING:
    from tests.ros2_backends import Tool, ToolPopen
from tests.test_ros2_bag_record import foxglove_decoded

Start = Callable[..., RclpyPeer]
pytest_plugins = ("tests.ros2_backends",)  # the `tool` and `backend` fixtures


def read_back(path: Path) -> dict[str, list[object]]:
    from rosbags.highlevel import AnyReader

    found: dict[str, list[object]] = {}
    with AnyReader([path]) as reader:
        for connection, _t, raw in reader.messages():
            found.setdefault(connection.topic, []).append(reader.deserialize(raw, connection.msgtype))
    return found


# the storage is the bag writer's business, not the backend's: .mcap covers the rclpy source
@pytest.mark.parametrize(("suffix", "backend"), [(".mcap", "dds"), (".mcap", "rclpy"), (".db3", "dds")])
def test_record_from_real_publishers(
    start_peer: Start, tmp_path: Path, suffix: str, tool_popen: ToolPopen, backend: str
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--stamped", "/pose", "--rate", "50")
    out = tmp_path / f"real{suffix}"
    recorder = Watched(tool_popen(["bag", "record", "/chatter", "/pose", "-O", str(out), "-q"]))
    try:
        # recording from when the talker sees the recorder on both topics, for 60 more messages (a fixed
        # window was eaten by discovery on a loaded machine)
        for topic in ("/chatter", "/pose"):
            talker.wait_for("matched", lambda e, t=topic: e["topic"] == t and e["subscribers"] > 0, 30)
        since = max(e["count"] for e in talker.of("matched") if e["topic"] == "/chatter")
        talker.wait_for("published", lambda e: e["count"] >= since + 60, timeout=30)
    finally:
        _out, err = recorder.stop(timeout=20)
    assert recorder.proc.returncode == 0, err
    recorded = read_back(out)
    # nothing lost between the first and the last message recorded (discovery takes about a second)
    numbers = [int(m.data.removeprefix("hello ")) for m in recorded["/chatter"]]  # type: ignore[attr-defined]
    assert len(numbers) >= 50 and numbers == list(range(numbers[0], numbers[0] + len(numbers)))
    xs = [m.point.x for m in recorded["/pose"]]  # type: ignore[attr-defined]
    assert xs == [float(x) for x in range(int(xs[0]), int(xs[0]) + len(xs))]
    assert {m.header.frame_id for m in recorded["/pose"]} == {"map"}  # type: ignore[attr-defined]
    if suffix == ".mcap":
        decoded = [m.data for topic, _schema, m in foxglove_decoded(out) if topic == "/chatter"]
        assert decoded == [f"hello {n}" for n in numbers]


def test_play_into_a_real_subscriber(start_peer: Start, tool: Tool, backend: str) -> None:
    peer = start_peer("--name", "listener", "--listen", "/topic")
    bag = TESTDATA / "ros2" / "talker_mcap"
    done = tool(["bag", "play", str(bag), "--topics", "/topic", "--wait-for-subscribers"])
    assert done.returncode == 0, done.stderr
    expected = [f"Hello, world! {n}" for n in range(10)]
    peer.wait_for("heard", lambda e: e["data"] == expected[-1])
    assert [e["data"] for e in peer.of("heard")] == expected


def test_delay_of_a_real_stamped_publisher(graph_env: dict[str, str], start_peer: Start) -> None:
    start_peer("--name", "stamper", "--stamped", "/pose", "--rate", "20")
    out = rostool(["topic", "delay", "/pose", "--duration", "3.2"], graph_env).stdout
    delays = [float(d) for d in re.findall(r"average delay: (-?[\d.]+)", out)]
    # same machine, same clock: the stamp is taken just before publishing, so the delay is small and positive
    assert delays and all(0 <= d < 0.05 for d in delays), out
