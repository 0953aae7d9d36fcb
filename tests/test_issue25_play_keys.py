"""Issue 25: `bag play`'s keys as rosbag2 has them, pressed in a real terminal (tmux): the right arrow plays
exactly the next message while paused, up/down change the rate by 10 % a press (status line), space
resumes; what arrives is checked with `topic echo` against the bag as rosbags reads it."""

from __future__ import annotations

import json
from pathlib import Path

from tests.support import TESTDATA, Watched, ros2_env, rostool_popen
from tests.terminal import Terminal

TALKER = TESTDATA / "ros2" / "talker_mcap"


def bag_strings(bag: Path, topic: str) -> list[str]:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [
            reader.deserialize(data, c.msgtype).data for c, _t, data in reader.messages(connections=conns)
        ]


def received(echo: Watched) -> list[str]:
    return [json.loads(line)["data"] for line in echo.stdout.splitlines() if line.startswith("{")]


def test_right_arrow_steps_and_up_down_change_the_rate(tmp_path: Path) -> None:
    env = ros2_env()
    expected = bag_strings(TALKER / "talker.mcap", "/topic")  # rosbags reads the file
    assert len(expected) == 10
    echo = Watched(rostool_popen(["--ros2", "topic", "echo", "/topic", "--json"], env))
    play = ["--ros2", "bag", "play", str(TALKER), "--topics", "/topic", "-p", "--wait-for-subscribers"]
    term = Terminal(play, env, tmp_path)
    try:
        assert term.wait_for(lambda s: "Press CURSOR_RIGHT for Play Next Message" in s, 60), term.screen()
        assert term.wait_for(lambda s: "[PAUSED ]" in s), term.screen()
        for step in (1, 2):
            term.send("Right")
            assert echo.wait_for(lambda out, n=step: out.count("\n") >= n, 20), echo.stdout
        term.send("Up")
        assert term.wait_for(lambda s: "Set rate to 1.1" in s and "Rate: 1.1" in s), term.screen()
        term.send("Down")
        term.send("Down")
        # 1.1 x 0.9 x 0.9
        assert term.wait_for(lambda s: "Set rate to 0.891" in s and "Rate: 0.891" in s), term.screen()
        assert received(echo) == expected[:2]  # still paused: exactly the two stepped messages
        term.send("Space")
        assert term.wait_for(lambda s: "[exit 0]" in s, 60), term.screen()
        assert echo.wait_for(lambda out: out.count("\n") >= 10, 20), echo.stdout
    finally:
        term.close()
        echo.stop()
    assert received(echo) == expected


def test_ros1_form_steps_with_the_right_arrow_and_shows_the_rate(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    """rosbag's form on a ROS 1 graph: Debian's rostopic echo receives exactly the stepped messages."""
    from tests.support import debian_popen
    from tests.test_bag_play import wait_subscribed, write_int_bag

    env = debian_master
    bag = write_int_bag(tmp_path / "numbers.bag", count=20, period_ns=100_000_000)
    echo = Watched(debian_popen(["rostopic", "echo", "/numbers/data"], env))
    term = Terminal(
        ["--ros1", "bag", "play", "--pause", "-d", "0", "--wait-for-subscribers", str(bag)], env, tmp_path
    )
    try:
        wait_subscribed(env, "/numbers")
        assert term.wait_for(lambda s: "Hit space to toggle paused" in s and "[PAUSED ]" in s, 30), (
            term.screen()
        )
        for step in (1, 2, 3):
            term.send("Right")
            assert echo.wait_for(lambda out, n=step: out.count("---") >= n, 10), echo.stdout
        term.send("Down")
        assert term.wait_for(lambda s: "Rate: 0.9" in s), term.screen()
        assert echo.stdout.split() == ["0", "---", "1", "---", "2", "---"]  # paused: nothing more
        term.send("Space")
        assert term.wait_for(lambda s: "Done." in s and "[exit 0]" in s, 30), term.screen()
        assert echo.wait_for(lambda out: out.count("---") >= 20, 10), echo.stdout
    finally:
        term.close()
        echo.stop()
    assert echo.stdout.split()[::2] == [str(i) for i in range(20)]
