"""The verbs that open endpoints start exactly when their endpoints match (issue 21): the first message after
the match is neither lost nor late, whatever discovery took. Real rclpy peers (Jazzy, Kilted; Fast DDS on
loopback), both of rostool's backends; the referee is the peer's own log of what it sent and when its
publisher saw the match (tests/rclpy_peer.py's `matched` and `published` events). Speed is bench/'s
(bench/bench_startup.py), not these tests'."""

from __future__ import annotations

import json
import signal
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.ros2_backends import Tool, ToolPopen
from tests.ros2_peers import RclpyPeer
from tests.support import Watched, rostool_popen, stop, wait_until

Start = Callable[..., RclpyPeer]


def first_match(talker: RclpyPeer, topic: str = "/t") -> int:
    """How many messages the talker had published when it first saw a subscriber (rostool's)."""
    event = talker.wait_for("matched", lambda e: e["topic"] == topic and e["subscribers"] >= 1, timeout=30)
    return int(event["count"])


def numbers_in_bag(directory: Path) -> list[int]:
    """The N of every 'hello N' (std_msgs/msg/String, CDR) in a rosbag2 directory's .mcap files, read with
    the mcap library."""
    from mcap.reader import make_reader

    found = []
    for path in sorted(directory.glob("*.mcap")):
        with path.open("rb") as stream:
            for _schema, _channel, message in make_reader(stream).iter_messages():
                (length,) = struct.unpack_from("<I", message.data, 4)
                text = message.data[8 : 8 + length - 1].decode()
                found.append(int(text.removeprefix("hello ")))
    return found


def test_echo_once_prints_the_first_message_sent_after_the_match(tool: Tool, start_peer: Start) -> None:
    talker = start_peer("--name", "talker", "--talk", "/t", "--rate", "10")
    done = tool(["topic", "echo", "/t", "--once", "--json"], timeout=60)
    assert done.returncode == 0, done.stderr
    shown = [json.loads(line)["data"] for line in done.stdout.splitlines() if line.startswith("{")]
    assert len(shown) == 1, done.stdout
    number = int(shown[0].removeprefix("hello "))
    matched = first_match(talker)
    # the talker checks its subscriber count right after each message: message `matched` or the next one
    # is the first the new subscription could get; an earlier one means it was not volatile's first
    assert matched - 2 <= number <= matched + 1, (number, matched)


def test_bag_record_keeps_every_message_sent_after_the_match(
    tool_popen: ToolPopen, start_peer: Start, tmp_path: Path
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/t", "--rate", "10")
    bag = tmp_path / "recorded"
    recorder = tool_popen(["bag", "record", "/t", "-o", str(bag)])
    try:
        matched = first_match(talker)
        talker.wait_for("published", lambda e: e["count"] >= matched + 20, timeout=30)
    finally:
        _out, err = stop(recorder, timeout=15)
    assert recorder.returncode in (0, 130), err
    numbers = numbers_in_bag(bag)
    assert numbers, err
    last = max(numbers)
    assert last >= matched + 20
    missing = sorted(set(range(matched + 1, last + 1)) - set(numbers))
    assert not missing, f"matched at {matched}: {missing} not recorded"
    assert min(numbers) >= matched - 2, (min(numbers), matched)  # nothing from before the subscription


@pytest.mark.alone  # a time window: --duration
def test_bag_record_duration_counts_from_the_match(tool: Tool, start_peer: Start, tmp_path: Path) -> None:
    """--duration 3 of a 10 Hz talker: the clock starts when the subscription matched, so the bag holds
    the first message sent after the match and the ~30 that follow it, none missing."""
    talker = start_peer("--name", "talker", "--talk", "/t", "--rate", "10")
    bag = tmp_path / "three_seconds"
    done = tool(["bag", "record", "/t", "--duration", "3", "-o", str(bag)], timeout=60)
    assert done.returncode == 0, done.stderr
    numbers = numbers_in_bag(bag)
    matched = first_match(talker)
    assert numbers and min(numbers) <= matched + 1, (numbers[:3], matched)
    assert numbers == list(range(min(numbers), max(numbers) + 1))
    assert len(numbers) >= 25, len(numbers)  # 30 on an idle machine (bench/bench_startup.py)


def test_bag_record_no_discovery_keeps_the_topics_present_at_start(
    tool_popen: ToolPopen, start_peer: Start, tmp_path: Path
) -> None:
    """`--no-discovery` records the topics published when it started, as discovery settled (a list frozen
    before discovery answered was empty on the DDS backend)."""
    talker = start_peer("--name", "talker", "--talk", "/t", "--rate", "10")
    bag = tmp_path / "present"
    recorder = tool_popen(["bag", "record", "-a", "--no-discovery", "-o", str(bag)])
    try:
        matched = first_match(talker)
        talker.wait_for("published", lambda e: e["count"] >= matched + 5, timeout=30)
    finally:
        _out, err = stop(recorder, timeout=15)
    assert recorder.returncode in (0, 130), err
    assert len(numbers_in_bag(bag)) >= 4, err


def test_pub_once_is_heard_by_the_real_listener(tool: Tool, start_peer: Start) -> None:
    listener = start_peer("--name", "listener", "--listen", "/heard")
    verb = ["topic", "pub", "--once", "/heard", "std_msgs/msg/String", "{data: 'just once'}"]
    done = tool(verb, timeout=60)
    assert done.returncode == 0, done.stderr
    assert listener.wait_for("heard")["data"] == "just once"
    assert [e["data"] for e in listener.of("heard")] == ["just once"]


def subscribers_seen(watcher: RclpyPeer, topic: str) -> list[str]:
    """The subscribers of `topic` in the watching node's latest view of the graph."""
    views: list[dict[str, Any]] = watcher.of("graph")
    return list(views[-1]["subscribers"].get(topic, [])) if views else []


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_an_exited_rostool_leaves_a_real_nodes_view_before_its_lease(
    graph_env: dict[str, str], start_peer: Start, sig: signal.Signals
) -> None:
    """The DDS backend's reader is disposed so that Fast DDS honours it (Cyclone sends key hashes): gone
    from a real node's view long before the 10 s lease that would otherwise remove it, whether the echo
    was ended by Ctrl+C or by SIGTERM (`timeout`, `kill`: it unwinds the same way, exit 143)."""
    start_peer("--name", "talker", "--talk", "/t", "--rate", "10")
    watcher = start_peer("--name", "watcher", "--watch")
    echo = Watched(rostool_popen(["topic", "echo", "/t"], graph_env))
    try:
        assert echo.wait_for(lambda out: "data: hello" in out, timeout=30), echo.stop()
        assert wait_until(lambda: subscribers_seen(watcher, "/t"), timeout=15), watcher.of("graph")[-1:]
        echo.proc.send_signal(sig)
        echo.proc.wait(timeout=10)
    finally:
        _out, err = echo.stop()
    assert echo.proc.returncode == (130 if sig == signal.SIGINT else 143), err
    assert "Traceback" not in err
    assert wait_until(lambda: not subscribers_seen(watcher, "/t"), timeout=5), watcher.of("graph")[-1]
