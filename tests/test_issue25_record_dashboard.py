"""Issue 25: `bag record --max-rate TOPIC:HZ` (per-topic throttling), the live dashboard on a terminal (tmux)
and the plain progress lines when stderr is not one, against real rclpy talkers; bags read with rosbags."""

from __future__ import annotations

import itertools
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from subprocess import PIPE, STDOUT

from tests.ros2_peers import RclpyPeer
from tests.support import Watched
from tests.terminal import Terminal

Start = Callable[..., RclpyPeer]


def bag_messages(bag: Path) -> dict[str, list[tuple[int, int]]]:
    """topic -> (receive time ns, N of "hello N") of each message, read by rosbags (not by rostool)."""
    from rosbags.highlevel import AnyReader

    found: dict[str, list[tuple[int, int]]] = {}
    with AnyReader([bag]) as reader:
        for conn, stamp, data in reader.messages():
            number = int(reader.deserialize(data, conn.msgtype).data.removeprefix("hello "))
            found.setdefault(conn.topic, []).append((stamp, number))
    return found


def published_after(peer: RclpyPeer, count: int) -> int:
    return int(peer.wait_for("published", lambda e: e["count"] > count, timeout=30)["count"])


def test_max_rate_throttles_one_topic_and_progress_lines_when_piped(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    fast = start_peer("--name", "fast", "--talk", "/fast", "--rate", "20")
    other = start_peer("--name", "other", "--talk", "/other", "--rate", "20")
    bag = tmp_path / "throttled.mcap"
    args = ["--ros2", "bag", "record", "/fast", "/other", "-o", str(bag), "--max-rate", "/fast:4"]
    command = [sys.executable, "-m", "rostool", *args, "--progress", "0.5"]
    recorder = Watched(subprocess.Popen(command, env=graph_env, stdout=PIPE, stderr=STDOUT, text=True))
    try:
        for peer in (fast, other):
            peer.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)
        # the first messages of both topics written (under load a Fast DDS writer that matched can take a
        # while to deliver: issue 37's subject, not this test's), then two seconds and more of both
        writing = re.compile(r"[1-9]\d* msgs on 2 topics")
        assert recorder.wait_for(lambda out: bool(writing.search(out)), 30), recorder.stdout
        # 40 more than the talker has said so far (not than its first report: a recorder that took long to
        # start would find those 40 in the past and be stopped at once)
        published_after(other, max((e["count"] for e in other.of("published")), default=0) + 40)
    finally:
        recorder.stop()
    assert re.search(r"rostool: recording \S+: \d+ msgs on 2 topics", recorder.stdout), recorder.stdout
    found = bag_messages(bag)
    fast_times = [t for t, _n in found["/fast"]]
    gaps = [b - a for a, b in itertools.pairwise(fast_times)]
    assert len(fast_times) >= 3 and min(gaps) >= 250_000_000, gaps  # 1/4 s between kept messages
    numbers = [n for _t, n in found["/other"]]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))  # the other topic: every message
    assert len(fast_times) < len(numbers) / 2


def test_dashboard_shows_each_topic_and_ends_with_the_bags_counts(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    fast = start_peer("--name", "fast", "--talk", "/fast", "--rate", "20")
    other = start_peer("--name", "other", "--talk", "/other", "--rate", "20")
    bag = tmp_path / "watched"
    term = Terminal(["--ros2", "bag", "record", "/fast", "/other", "-o", str(bag)], graph_env, tmp_path)
    try:
        for peer in (fast, other):
            peer.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)

        def both_counting(screen: str) -> bool:
            rows = dict(re.findall(r"^  (/fast|/other) +(\d+) +[\d.]+/s", screen, re.M))
            return len(rows) == 2 and min(map(int, rows.values())) >= 10

        assert term.wait_for(both_counting, 30), term.screen()
        screen = term.screen()
        assert re.search(r"^  topic +msgs +rate +bandwidth +written +dropped", screen, re.M), screen
        term.send("C-c")
        assert term.wait_for(lambda s: "[exit 0]" in s, 30), term.screen()
        screen = term.screen()
    finally:
        term.close()
    last = {topic: int(count) for topic, count in re.findall(r"^  (/fast|/other) +(\d+) ", screen, re.M)}
    counts = {topic: len(rows) for topic, rows in bag_messages(bag).items()}
    assert last == counts, (last, counts)
    assert f"recorded {sum(counts.values())} messages on 2 topics" in screen
