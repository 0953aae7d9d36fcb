"""`bag record` from the first instant (issue 37): while a graph daemon serves, a recording's topics come
through relays, readers in the daemon's graph that already knows their publishers, so the recorder does
not wait for its own participant to be discovered and matched (measured without: the first message
1.0-3.7 s after start; with: 0.65-0.85 s, bench/RESULTS.md). Referee: real rclpy talkers (Jazzy, Kilted)
on both backends: the talkers see only the daemon's reader (never the recorder's own participant), the bag
holds every message from the one published as that reader matched, without a gap, read back by rosbags,
with the publishers' QoS (a latched talker's transient_local) in its metadata; -a finds the topics in the
daemon's graph; --duration counts from when the relays record."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from tests.ros2_backends import Tool
from tests.ros2_peers import RclpyPeer
from tests.support import wait_until
from tests.test_daemon import graph_env  # noqa: F401 (the fixture: the daemon allowed, its own directory)
from tests.test_daemon_relay import BARE, DAEMON_NODE, started_daemon


def recorded(path: Path) -> tuple[dict[str, list[int]], dict[str, str], dict[str, str]]:
    """Per topic: the N of each 'hello N' in order, the type, and the offered durability, as rosbags reads
    the bag."""
    from rosbags.highlevel import AnyReader

    numbers: dict[str, list[int]] = {}
    with AnyReader([path]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        durability = {
            c.topic: ",".join(sorted({q.durability.name for q in c.ext.offered_qos_profiles}))
            for c in reader.connections
        }
        for conn, _stamp, raw in reader.messages():
            if conn.msgtype == "std_msgs/msg/String":
                data = reader.deserialize(raw, conn.msgtype).data
                numbers.setdefault(conn.topic, []).append(int(data.split()[1]))
    return numbers, types, durability


def subscribers_seen(talker: RclpyPeer, topic: str) -> set[str]:
    """Every node the talker's own graph views showed subscribed to `topic`."""
    return {node for view in talker.of("graph") for node in view["subscribers"].get(topic, [])}


def test_a_recording_through_the_daemon_starts_at_its_first_message(
    tool: Tool,
    start_peer: Callable[..., RclpyPeer],
    graph_env: dict[str, str],  # noqa: F811
    tmp_path: Path,
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "10", "--watch")
    latched = start_peer("--name", "keeper", "--talk", "/kept", "--rate", "10", "--latched")
    started_daemon(tool)
    assert wait_until(lambda: "/kept" in tool(["--ros2", "topic", "list"]).stdout, timeout=20)
    bag = tmp_path / "first.mcap"
    began = len(talker.of("matched"))
    done = tool(["--ros2", "bag", "record", "-a", "--duration", "2", "-o", str(bag)], timeout=60)
    assert done.returncode == 0, done.stderr

    numbers, types, durability = recorded(bag)
    assert types["/chatter"] == types["/kept"] == "std_msgs/msg/String", types
    assert durability["/kept"] == "TRANSIENT_LOCAL" and durability["/chatter"] == "VOLATILE", durability
    for topic, peer in (("/chatter", talker), ("/kept", latched)):
        got = numbers[topic]
        assert got == list(range(got[0], got[0] + len(got))), (topic, got)  # no gap
        # --duration 2 counted from when the relays recorded: at least 2 s of a 10 Hz topic (and the latched
        # talker's 10 kept messages, which a late subscriber gets first); a busy recorder that reads its
        # relays late starts the clock late, and holds a few more
        assert len(got) - (10 if peer is latched else 0) >= 19, (topic, got)
        if peer is talker:  # the first message is the one published as the daemon's reader matched it
            joined = [e for e in talker.of("matched")[began:] if e["subscribers"] == 1]
            assert joined, talker.of("matched")
            assert got[0] <= joined[0]["count"] + 1, (got[0], joined[0])

    # the recorder never joined the graph itself: the talker saw only the daemon's reader on /chatter
    time.sleep(1.0)  # one more of the talker's views (every 0.5 s) after the recording ended
    seen = subscribers_seen(talker, "/chatter")
    assert seen and all(node.startswith(DAEMON_NODE) or BARE in node for node in seen), seen
