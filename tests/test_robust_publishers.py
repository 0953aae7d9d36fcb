"""Several publishers on one topic (issue 27): `bag record` keeps every message of every publisher in every
format (.mcap/.db3 share one connection per topic; .bag keeps one per publisher, as rosbag does)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.support import rostool_popen, start_rospy_script, stop

EACH = 20
NAMES = ("alpha", "beta", "gamma")
# Waits for the recorder, then publishes EACH 'NAME:i' strings.
NAMED_PUBLISHER = """
import sys
import rospy
from std_msgs.msg import String
topic, name, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
rospy.init_node(name)
pub = rospy.Publisher(topic, String, queue_size=count)
while pub.get_num_connections() == 0 and not rospy.is_shutdown():
    rospy.sleep(0.05)
rate = rospy.Rate(50)
for i in range(count):
    pub.publish(String(data='%s:%d' % (name, i)))
    rate.sleep()
rospy.spin()
"""


def _strings(path: Path) -> list[str]:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if path.suffix == ".bag" else Stores.ROS2_JAZZY)
    with AnyReader([path], default_typestore=store) as reader:
        return [str(reader.deserialize(raw, c.msgtype).data) for c, _t, raw in reader.messages()]


@pytest.mark.parametrize("fmt", ["bag", "mcap", "db3"])
def test_every_publisher_of_a_topic_is_recorded(
    debian_master: dict[str, str], tmp_path: Path, fmt: str
) -> None:
    env = {**debian_master, "ROS_VERSION": "1"}
    out = tmp_path / f"many.{fmt}"
    recorder = rostool_popen(["bag", "record", "/many", "-O", str(out), "-l", str(EACH * len(NAMES))], env)
    publishers = [
        start_rospy_script(NAMED_PUBLISHER, env, tmp_path, name, ["/many", name, str(EACH)]) for name in NAMES
    ]
    try:
        _out, err = recorder.communicate(timeout=60)  # ends by itself at 60 messages
    finally:
        for publisher in publishers:
            stop(publisher)
    assert recorder.returncode == 0, err
    assert "cannot write" not in err, err
    strings = _strings(out)
    for name in NAMES:
        assert [s for s in strings if s.startswith(f"{name}:")] == [f"{name}:{i}" for i in range(EACH)]


@pytest.mark.parametrize("fmt", ["mcap", "db3"])
def test_every_rclpy_publisher_of_a_topic_is_recorded(
    start_peer: Callable[..., Any], graph_env: dict[str, str], tmp_path: Path, fmt: str
) -> None:
    """Two real rclpy talkers on one topic: both bursts are in the ROS 2 bag, each 'hello N' twice."""
    out = tmp_path / f"two.{fmt}"
    recorder = rostool_popen(
        ["bag", "record", "--topics", "/two", "-O", str(out), "--duration", "8"], graph_env
    )
    talkers = ["--talk", "/two", "--count", "30", "--depth", "100", "--subs", "1"]
    peers = [start_peer("--name", name, *talkers) for name in ("first", "second")]
    for peer in peers:  # each burst starts once the recorder's subscription matched it
        peer.wait_for("sent", timeout=30)
    _out, err = recorder.communicate(timeout=60)
    assert recorder.returncode == 0, err
    assert "cannot write" not in err, err
    counts = Counter(_strings(out))
    assert len(counts) == 30 and set(counts.values()) == {2}, counts
