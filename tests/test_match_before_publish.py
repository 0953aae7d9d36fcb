"""Nothing lost at the start (issue 37): `bag play` and `topic pub` publish their first message only once
their writer has matched the subscriptions the graph showed when they started (at most --match-wait s).
Referee: a real rclpy node that subscribed before rostool started, counting what it heard, on Jazzy and
Kilted, through both backends. Without the wait, a Fast DDS subscriber missed the first messages: 8/10 of
a played bag, the first of a --start-offset play, the first pass of a --loop, 3 of a 1 Hz `--ros2 topic
pub` that ran 4.5 s."""

from __future__ import annotations

import time
import xmlrpc.client
from collections.abc import Callable

from tests.ros2_backends import Tool, ToolPopen
from tests.ros2_peers import RclpyPeer
from tests.support import TESTDATA, rostool, stop

TALKER = TESTDATA / "ros2" / "talker_mcap"  # /topic: 'Hello, world! 0' .. 9, one a second


def test_play_and_pub_reach_a_subscriber_that_was_there_from_the_first_message(
    tool: Tool, tool_popen: ToolPopen, start_peer: Callable[..., RclpyPeer]
) -> None:
    listener = start_peer("--name", "listener", "--listen", "/topic")
    played = tool(["--ros2", "bag", "play", "-r", "5", "--topics", "/topic", str(TALKER)])
    assert played.returncode == 0, played.stderr
    expected = [f"Hello, world! {i}" for i in range(10)]
    listener.wait_for("heard", lambda e: e["data"] == expected[-1], timeout=10)
    assert [e["data"] for e in listener.of("heard")] == expected

    # --start-offset: exactly the messages from that bag time on, the first one included
    heard = len(listener.of("heard"))
    played = tool(
        ["--ros2", "bag", "play", "-r", "5", "--start-offset", "2.25", "--topics", "/topic", str(TALKER)]
    )
    assert played.returncode == 0, played.stderr
    from rostool.bag.reader import BagReader

    with BagReader([TALKER]) as reader:
        start = reader.start_ns
        offset = [
            reader.deserialize(raw, conn).data  # type: ignore[attr-defined]
            for conn, stamp, raw in reader.messages(reader.select(["/topic"]))
            if stamp >= start + 2.25e9
        ]
    listener.wait_for("heard", lambda _e: len(listener.of("heard")) - heard >= len(offset), timeout=10)
    assert [e["data"] for e in listener.of("heard")[heard:]] == offset

    # --loop: whole passes from the first message, until Ctrl+C
    heard = len(listener.of("heard"))
    loop = tool_popen(["--ros2", "bag", "play", "--loop", "-r", "10", "--topics", "/topic", str(TALKER)])
    listener.wait_for("heard", lambda _e: len(listener.of("heard")) - heard >= 15, timeout=20)
    stop(loop)
    looped = [e["data"] for e in listener.of("heard")[heard:]]
    assert looped == [expected[k % 10] for k in range(len(looped))], looped

    # ros2 topic pub's form (1 Hz until Ctrl+C): stopped 0.3 s after it said it published #3, the
    # listener must have heard all three
    pub = tool_popen(["--ros2", "topic", "pub", "/topic", "std_msgs/msg/String", "data: pub"])
    assert pub.stdout is not None
    third = next((line for line in pub.stdout if line.startswith("publishing #3:")), None)
    time.sleep(0.3)
    _out, err = stop(pub)
    assert third, err
    said = [e for e in listener.of("heard") if e["data"] == "pub"]
    assert len(said) == 3, (said, err)


def test_a_subscriber_that_never_connects_is_named_in_one_warning(debian_master: dict[str, str]) -> None:
    """ROS 1: a subscriber the master lists whose node cannot be reached (registered at Debian's rosmaster
    with an address nobody serves) never connects: `topic pub` waits --match-wait seconds, then publishes
    anyway with one warning naming it; --match-wait 0 does not wait or warn."""
    env = debian_master
    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    code, _msg, _pubs = master.registerSubscriber("/ghost", "/said", "std_msgs/String", "http://127.0.0.1:9/")
    assert code == 1
    pub = ["topic", "pub", "/said", "std_msgs/String", "data: hi", "-r", "10", "-n", "2"]
    began = time.monotonic()
    waited = rostool([*pub, "--match-wait", "1"], env)
    assert waited.returncode == 0, waited.stderr
    assert time.monotonic() - began >= 1.0
    assert waited.stderr.splitlines() == [
        "rostool: warning: not every subscriber had matched within 1 s, publishing anyway: /said (/ghost) "
        "(--match-wait S waits longer, 0 not at all)"
    ]
    at_once = rostool([*pub, "--match-wait", "0"], env)
    assert at_once.returncode == 0 and at_once.stderr == "", at_once.stderr
