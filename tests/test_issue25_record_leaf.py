"""Issue 25: `ros2 bag record -a --ignore-leaf-topics` leaves out a real talker's topic while no node
subscribes to it, and records it once a real listener does; the bag read with rosbags."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from tests.ros2_peers import RclpyPeer
from tests.support import rostool_popen, stop

Start = Callable[..., RclpyPeer]


def test_ignore_leaf_topics(graph_env: dict[str, str], start_peer: Start, tmp_path: Path) -> None:
    from rosbags.highlevel import AnyReader

    heard = start_peer("--name", "heard", "--talk", "/heard", "--rate", "20")
    start_peer("--name", "listener", "--listen", "/heard")
    leaf = start_peer("--name", "leaf", "--talk", "/leaf", "--rate", "20")
    bag = tmp_path / "leafless"
    recorder = rostool_popen(
        ["--ros2", "bag", "record", "-a", "--ignore-leaf-topics", "-o", str(bag)], graph_env
    )
    try:
        both = heard.wait_for("matched", lambda e: e["subscribers"] >= 2, timeout=30)  # listener, recorder
        heard.wait_for("published", lambda e: e["count"] > both["count"] + 20, timeout=30)
        # a second and more after /heard was taken, /leaf still has only its talker: not recorded
        assert not [e for e in leaf.of("matched") if e["subscribers"] > 0]
        start_peer("--name", "late", "--listen", "/leaf")
        taken = leaf.wait_for(
            "matched", lambda e: e["subscribers"] >= 2, timeout=30
        )  # late listener, rostool
        leaf.wait_for("published", lambda e: e["count"] > taken["count"] + 10, timeout=30)
    finally:
        stop(recorder)
    with AnyReader([bag]) as reader:
        topics = {c.topic for c in reader.connections}
        counts = {t: sum(1 for c, _t, _d in reader.messages() if c.topic == t) for t in topics}
    assert {"/heard", "/leaf"} <= topics, topics
    assert counts["/heard"] >= 20 and counts["/leaf"] >= 1, counts
