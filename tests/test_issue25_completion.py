"""Issue 25's new words complete through the real mechanism (tests/test_completion.py's `complete`): bag
burst's bag topics, bag info --sort's methods, topic bw's several topics from a real ROS 1 master."""

from __future__ import annotations

import os

from tests.support import debian_popen, stop, wait_until
from tests.test_completion import EXAMPLE_BAG, TALKER_MCAP, bag_topics, values


def test_burst_topics_and_info_sort() -> None:
    env = dict(os.environ)
    ros2_topics = bag_topics(TALKER_MCAP)
    assert values(["--ros2", "bag", "burst", str(TALKER_MCAP), "--topics", ""], env) == ros2_topics
    assert values(["bag", "burst", str(EXAMPLE_BAG), "--topics", "/turtle1/c"], env) == [
        t for t in bag_topics(EXAMPLE_BAG) if t.startswith("/turtle1/c")
    ]
    assert values(["bag", "info", str(EXAMPLE_BAG), "--sort", ""], env) == ["name", "type", "count"]


def test_bw_completes_a_second_topic(debian_master: dict[str, str]) -> None:
    env = debian_master
    publisher = debian_popen(["rostopic", "pub", "-r", "5", "/beat", "std_msgs/String", "data: x"], env)
    try:
        assert wait_until(lambda: "/beat" in values(["--ros1", "topic", "bw", "/rosout", "/b"], env), 30)
        assert "/beat" in values(["--ros1", "topic", "hz", "--all", "/beat", "/b"], env)
    finally:
        stop(publisher)
