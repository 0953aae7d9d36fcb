"""Issue 25: `ros2 bag record --snapshot-mode`: the newest messages are held in memory (here the last
second, --max-cache-duration 1) and written only when a snapshot is asked for (SIGUSR2; 's' on a
terminal); against a real rclpy talker, the bag read with rosbags."""

from __future__ import annotations

import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from subprocess import PIPE, STDOUT

from tests.ros2_peers import RclpyPeer
from tests.support import Watched

Start = Callable[..., RclpyPeer]


def published_after(peer: RclpyPeer, count: int) -> int:
    return int(peer.wait_for("published", lambda e: e["count"] > count, timeout=30)["count"])


def test_snapshots_write_the_last_second_only(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    from rosbags.highlevel import AnyReader

    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    bag = tmp_path / "snap"
    args = [
        "--ros2",
        "bag",
        "record",
        "/chatter",
        "-o",
        str(bag),
        "--snapshot-mode",
        "--max-cache-duration",
        "1",
    ]
    recorder = Watched(
        subprocess.Popen(
            [sys.executable, "-m", "rostool", *args], env=graph_env, stdout=PIPE, stderr=STDOUT, text=True
        )
    )
    try:
        matched = int(talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)["count"])
        first = published_after(talker, matched + 60)  # three seconds: two of them no longer held
        recorder.proc.send_signal(signal.SIGUSR2)
        assert recorder.wait_for(lambda out: out.count("Taking a snapshot.") == 1, 10), recorder.stdout
        second = published_after(talker, published_after(talker, first) + 60)
        recorder.proc.send_signal(signal.SIGUSR2)
        assert recorder.wait_for(lambda out: out.count("Taking a snapshot.") == 2, 10), recorder.stdout
        published_after(talker, second + 40)  # messages after the last snapshot are never written
    finally:
        recorder.stop()
    assert "Snapshot mode: messages are held in memory" in recorder.stdout
    with AnyReader([bag]) as reader:
        rows = [
            (stamp, int(reader.deserialize(data, conn.msgtype).data.removeprefix("hello ")))
            for conn, stamp, data in reader.messages()
        ]
    numbers = [n for _t, n in rows]
    split = next(i for i in range(1, len(numbers)) if numbers[i] != numbers[i - 1] + 1)
    groups = [rows[:split], rows[split:]]
    for group in groups:  # each snapshot: consecutive messages received within one second
        assert group[-1][0] - group[0][0] <= 1_000_000_000, group
        assert [n for _t, n in group] == list(range(group[0][1], group[0][1] + len(group)))
    assert min(numbers) > matched + 20 and groups[0][-1][1] <= first + 20 < groups[1][0][1], (
        matched,
        first,
        numbers,
    )
    assert max(numbers) <= second + 20, (second, numbers)


def test_s_key_takes_a_snapshot_in_a_terminal(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    from rosbags.highlevel import AnyReader

    from tests.terminal import Terminal

    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    bag = tmp_path / "keyed"
    term = Terminal(
        ["--ros2", "bag", "record", "/chatter", "-o", str(bag), "--snapshot-mode"], graph_env, tmp_path
    )
    try:
        assert term.wait_for(lambda s: "written when 's' or SIGUSR2" in s, 30), term.screen()
        matched = int(talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)["count"])
        asked = published_after(talker, matched + 20)
        assert term.wait_for(lambda s: "[SNAPSHOT MODE: " in s), term.screen()
        term.send("s")
        assert term.wait_for(lambda s: "Taking a snapshot." in s), term.screen()
        published_after(talker, asked + 20)
        term.send("C-c")
        assert term.wait_for(lambda s: "[exit 0]" in s, 30), term.screen()
    finally:
        term.close()
    with AnyReader([bag]) as reader:
        numbers = [
            int(reader.deserialize(d, c.msgtype).data.removeprefix("hello "))
            for c, _t, d in reader.messages()
        ]
    # no duration limit: everything from the subscription on, up to the key press
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers))) and len(numbers) >= 20, numbers
    assert numbers[-1] < asked + 40, (asked, numbers[-1])
