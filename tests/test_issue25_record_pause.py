"""Issue 25: `bag record --start-paused` (ros2 bag record's flag) in a real terminal: nothing is recorded
until SPACE, then every message of a real rclpy talker is; SIGUSR1 does the same without a terminal. The
bags are read with rosbags' own reader."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from subprocess import PIPE, STDOUT

from tests.ros2_peers import RclpyPeer
from tests.support import Watched
from tests.terminal import Terminal

Start = Callable[..., RclpyPeer]


def recorded_numbers(bag: Path) -> list[int]:
    """N of each "hello N" in the bag, read by rosbags (not by rostool)."""
    return [number for _stamp, number in recorded(bag)]


def recorded(bag: Path) -> list[tuple[int, int]]:
    """Each message's log time (its receive time, ns since the epoch) and N of its "hello N", read by
    rosbags."""
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:
        return [
            (stamp, int(reader.deserialize(data, conn.msgtype).data.removeprefix("hello ")))
            for conn, stamp, data in reader.messages()
        ]


def published_after(peer: RclpyPeer, count: int) -> int:
    """Wait for the talker's report of having published more than `count` messages; its count."""
    return int(peer.wait_for("published", lambda e: e["count"] > count, timeout=30)["count"])


def test_record_start_paused_records_from_space_on(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    bag = tmp_path / "paused"
    term = Terminal(
        ["--ros2", "bag", "record", "/chatter", "-o", str(bag), "--start-paused"], graph_env, tmp_path
    )
    try:
        assert term.wait_for(lambda s: "Press SPACE for pausing/resuming. Recording is paused." in s), (
            term.screen()
        )
        matched = talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)
        # messages up to `before` were published at least a second before SPACE: none may be recorded
        before = published_after(talker, int(matched["count"]) + 20)
        resumed = published_after(talker, before + 20)
        term.send("Space")
        assert term.wait_for(lambda s: "[INFO] [rosbag2_recorder]: Resuming recording." in s), term.screen()
        published_after(talker, resumed + 20)
        term.send("C-c")
        assert term.wait_for(lambda s: "[exit 0]" in s, 30), term.screen()
    finally:
        term.close()
    numbers = recorded_numbers(bag)
    assert len(numbers) >= 20 and min(numbers) > before, (before, numbers[:5])
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))  # nothing lost once resumed


def test_record_pauses_and_resumes_on_sigusr1(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    bag = tmp_path / "signalled.mcap"
    command = [sys.executable, "-m", "rostool", "--ros2", "bag", "record", "/chatter", "-o", str(bag)]
    # its stderr (where the pause lines go) read as its stdout
    recorder = Watched(subprocess.Popen(command, env=graph_env, stdout=PIPE, stderr=STDOUT, text=True))
    try:
        matched = talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)
        first = published_after(talker, int(matched["count"]) + 10)
        recorder.proc.send_signal(signal.SIGUSR1)
        assert recorder.wait_for(lambda out: "Pausing recording." in out, 10), recorder.stdout
        # paused from here (the recorder prints the line once paused) to `resuming`: a message received in
        # between (the bag's log time is its receive time, on this machine's clock) must not be recorded.
        # Counts alone cannot bound it: a "published" event seen after the line may be of a message sent
        # before the pause, and one sent before the resume may be received after it.
        paused = time.time_ns()
        paused_at = published_after(talker, max(int(e["count"]) for e in talker.of("published")))
        resumed_at = published_after(talker, paused_at + 20)  # a second of messages no one should record
        resuming = time.time_ns()
        recorder.proc.send_signal(signal.SIGUSR1)
        assert recorder.wait_for(lambda out: "Resuming recording." in out, 10), recorder.stdout
        published_after(talker, resumed_at + 20)
    finally:
        recorder.stop()
    found = recorded(bag)
    numbers = [number for _stamp, number in found]
    gap = [(number, stamp - paused) for stamp, number in found if paused <= stamp <= resuming]
    assert not gap, gap
    assert numbers == sorted(numbers), numbers
    # and by counts: all but the edges of that second left out (a message of either edge may have been
    # sent before the pause, or received after the resume)
    missed = set(range(paused_at + 1, resumed_at + 1)) - set(numbers)
    assert len(missed) >= resumed_at - paused_at - 4, (paused_at, resumed_at, numbers)
    assert any(n <= first for n in numbers) and any(n > resumed_at for n in numbers), numbers
