"""Issue 25: after `bag play` ends its publishers leave a real node's graph at once (not after a DDS lease
of 10 s), and `bag record` stores each volatile topic's offered QoS in metadata.yaml (read with rosbags)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from tests.ros2_peers import RclpyPeer
from tests.support import TESTDATA, rostool, rostool_popen, stop, wait_until

Start = Callable[..., RclpyPeer]
TALKER = TESTDATA / "ros2" / "talker_mcap"


def publishes_topic(event: dict[str, Any]) -> bool:
    return bool(event.get("publishers", {}).get("/topic"))


def test_played_publishers_leave_the_graph_at_once(graph_env: dict[str, str], start_peer: Start) -> None:
    watcher = start_peer("--name", "watcher", "--watch")
    played = rostool(["--ros2", "bag", "play", str(TALKER), "--topics", "/topic", "-r", "5"], graph_env)
    assert played.returncode == 0, played.stderr
    assert watcher.wait_for("graph", publishes_topic), "the real node never saw the player's publisher"
    after = len(watcher.events)

    def left() -> bool:
        views = [e for e in watcher.events[after:] if e["event"] == "graph"]
        return bool(views) and not publishes_topic(views[-1])

    # the watcher reports its graph every 0.5 s; a publisher left to the lease would stay 10 s
    assert wait_until(left, 5.0), [e for e in watcher.events[after:] if e["event"] == "graph"][-1:]


def test_volatile_topics_record_their_offered_qos(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    from rosbags.interfaces import QosDurability, QosReliability
    from rosbags.rosbag2 import Reader

    reliable = start_peer("--name", "reliable", "--talk", "/reliable", "--rate", "20")
    best_effort = start_peer("--name", "lossy", "--talk", "/lossy", "--rate", "20", "--best-effort")
    latched = start_peer("--name", "latched", "--talk", "/latched", "--rate", "20", "--latched")
    bag = tmp_path / "qos"
    recorder = rostool_popen(
        ["--ros2", "bag", "record", "/reliable", "/lossy", "/latched", "-o", str(bag)], graph_env
    )
    try:
        for peer in (reliable, best_effort, latched):
            matched = peer.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)
            peer.wait_for("published", lambda e, m=matched: e["count"] > m["count"] + 5, timeout=30)
    finally:
        stop(recorder)
    with Reader(bag) as reader:
        offered = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}  # type: ignore[union-attr]
    got = {topic: [(q.reliability, q.durability) for q in profiles] for topic, profiles in offered.items()}
    assert got == {
        "/reliable": [(QosReliability.RELIABLE, QosDurability.VOLATILE)],
        "/lossy": [(QosReliability.BEST_EFFORT, QosDurability.VOLATILE)],
        "/latched": [(QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL)],
    }
