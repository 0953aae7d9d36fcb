"""`rostool bag record` from a real ROS 1 graph; the bags are checked with Debian's rosbag and rostopic."""

from __future__ import annotations

import json
import re
import resource
import signal
import subprocess
import time
from pathlib import Path

import yaml

from tests.peers import HELLO_PUBLISHER
from tests.support import (
    Watched,
    debian,
    debian_popen,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
    wait_until,
)
from tests.test_bag_play import (
    COUNTER_PUBLISHER,
    TIMED_SUBSCRIBER,
    bag_values,
    echo_strings,
    no_traceback,
    nodes_on,
    timed_values,
    wait_published,
    wait_subscribed,
)

# Publishes String "N:xxxx..." of SIZE bytes on TOPIC at RATE Hz.
BIG_PUBLISHER = """
import sys
import rospy
from std_msgs.msg import String
topic, rate, size = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
rospy.init_node('big', anonymous=True)
pub = rospy.Publisher(topic, String, queue_size=100)
period = rospy.Rate(rate)
i = 0
while not rospy.is_shutdown():
    head = '%d:' % i
    pub.publish(String(data=head + 'x' * (size - len(head))))
    i += 1
    period.sleep()
"""

# The book's W9 nodes (chapter 16): a temperature publisher and a subscriber that publishes the status
# against the /threshold_temp parameter (faster than the book's 1 Hz).
TEMPERATURE_PUBLISHER = """
import sys
import rospy
from std_msgs.msg import Float32
rospy.init_node('temperature_publisher', anonymous=True)
pub = rospy.Publisher('current_temperature', Float32, queue_size=10)
rate = rospy.Rate(float(sys.argv[1]))
temp = 15.0
while not rospy.is_shutdown():
    pub.publish(Float32(temp))
    temp = temp + 1.0 if temp < 45.0 else 15.0
    rate.sleep()
"""

TEMPERATURE_SUBSCRIBER = """
import rospy
from std_msgs.msg import Float32, String
rospy.init_node('temperature_subscriber', anonymous=True)
status = rospy.Publisher('temperature_status', String, queue_size=10)
def on(data):
    threshold_temp = rospy.get_param('/threshold_temp', 30.0)
    alert = 'ALERT' if data.data > threshold_temp else 'OK'
    status.publish(String(data=f'{data.data},{threshold_temp},{alert}'))
rospy.Subscriber('current_temperature', Float32, on)
rospy.spin()
"""

DATE = r"\d{4}-\d{2}-\d{2}-\d{2}-\d{2}-\d{2}"


def debian_info(path: Path, env: dict[str, str]) -> dict[str, object]:
    result = debian(["rosbag", "info", "--yaml", str(path)], env)
    assert result.returncode == 0, result.stderr
    return yaml.safe_load(result.stdout)  # type: ignore[no-any-return]


def topic_table(info: dict[str, object]) -> dict[str, tuple[str, int]]:
    return {t["topic"]: (t["type"], t["messages"]) for t in info["topics"]}  # type: ignore[attr-defined]


def record(env: dict[str, str], cwd: Path, args: list[str], **kwargs: object) -> subprocess.Popen[str]:
    return rostool_popen(["bag", "record", *args], env, cwd=cwd, **kwargs)


def wait_recording(env: dict[str, str], topic: str) -> None:
    """Our recorder has subscribed to `topic` (connections follow within milliseconds)."""
    wait_subscribed(env, topic)
    time.sleep(0.5)


def finish(proc: subprocess.Popen[str], sig: int = signal.SIGINT) -> tuple[str, str]:
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    return out, err


# -- tests ---------------------------------------------------------------------------------------
def test_recorded_bag_opens_and_plays_in_debian_rosbag(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    hello = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    chatter = rostool_popen(["topic", "pub", "/chatter", "std_msgs/String", "data: hi", "-r", "10"], env)
    try:
        wait_published(env, "/hello_world")
        wait_published(env, "/chatter")
        recorder = record(env, tmp_path, ["/hello_world", "/chatter", "-O", "out.bag"])
        wait_recording(env, "/chatter")
        time.sleep(2.5)
        _out, err = finish(recorder)
    finally:
        stop(hello)
        stop(chatter)
    bag = tmp_path / "out.bag"
    assert not (tmp_path / "out.bag.active").exists()
    assert err.startswith("recorded ") and "out.bag" in err  # one summary line, no progress when piped
    hellos, his = bag_values(bag, "/hello_world"), bag_values(bag, "/chatter")
    assert len(hellos) >= 8 and len(his) >= 15 and set(his) == {"hi"}
    numbers = [int(v.removeprefix("Hello_World_")) for v in hellos]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))  # none lost, none doubled
    info = debian_info(bag, env)
    assert topic_table(info) == {
        "/hello_world": ("std_msgs/String", len(hellos)),
        "/chatter": ("std_msgs/String", len(his)),
    }
    assert info["messages"] == len(hellos) + len(his) and info["indexed"] is True
    ours = json.loads(rostool(["bag", "info", "--json", str(bag)], env).stdout)
    assert ours["messages"] == len(hellos) + len(his)
    # Debian's rosbag play publishes exactly the recorded values
    echo = Watched(debian_popen(["rostopic", "echo", "/hello_world"], env))
    try:
        wait_subscribed(env, "/hello_world")
        played = debian(["rosbag", "play", "-d", "1", "-r", "4", str(bag)], env, timeout=60)
        assert played.returncode == 0, played.stderr
        echo.wait_for(lambda text: len(echo_strings(text)) >= len(hellos), 10)
    finally:
        out, _err = echo.stop()
    assert echo_strings(out) == hellos


def run_in(cwd: Path, args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    proc = rostool_popen(args, env, cwd=cwd)
    out, err = proc.communicate(timeout=30)
    return subprocess.CompletedProcess(args, proc.returncode, out, err)


def test_output_names_like_rosbag(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    for args in (["-o", "test.bag"], ["-O", "test.bag"], ["-O", "exact"], ["-o", "pre"], []):
        result = run_in(tmp_path, ["bag", "record", "/none", "--duration", "0.3", *args], env)
        assert result.returncode == 0, result.stderr
        no_traceback(result)
    names = sorted(p.name for p in tmp_path.glob("*.bag*"))
    assert len(names) == 5, names
    assert "test.bag" in names and "exact.bag" in names
    assert any(re.fullmatch(f"test_{DATE}.bag", n) for n in names)
    assert any(re.fullmatch(f"pre_{DATE}.bag", n) for n in names)
    assert any(re.fullmatch(f"{DATE}.bag", n) for n in names)
    for name in names:  # an empty bag, as rosbag's own: no chunks (`indexed: False` is rosbag's view)
        assert debian_info(tmp_path / name, env)["version"] == 2.0


def test_all_topics_includes_late_ones_and_split_by_size(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    env = debian_master
    recorder = record(env, tmp_path, ["-a", "-x", "/rosout.*", "-O", "late.bag"])
    late = None
    try:
        assert wait_until(lambda: (tmp_path / "late.bag.active").exists(), 20)
        time.sleep(1.0)  # recording before the topic exists
        late = rostool_popen(["topic", "pub", "/late", "std_msgs/String", "data: late", "-r", "20"], env)
        wait_published(env, "/late")
        assert wait_until(lambda: "/late" in [t for t, nodes in _subscribed(env)], 10)
        time.sleep(1.5)
        finish(recorder)
    finally:
        if late is not None:
            stop(late)
    values = bag_values(tmp_path / "late.bag", "/late")
    assert len(values) >= 10 and set(values) == {"late"}
    assert "/rosout" not in topic_table(debian_info(tmp_path / "late.bag", env))

    big = start_rospy_script(BIG_PUBLISHER, env, tmp_path, "big", ["/big", "100", "10000"])
    try:
        wait_published(env, "/big")
        recorder = record(env, tmp_path, ["/big", "-O", "parts.bag", "--split", "--size", "0.2"])
        wait_recording(env, "/big")
        time.sleep(1.5)
        finish(recorder)
    finally:
        stop(big)
    parts = sorted(tmp_path.glob("parts_*.bag"), key=lambda p: int(p.stem.split("_")[1]))
    assert len(parts) >= 4, parts
    assert [p.name for p in parts] == [f"parts_{i}.bag" for i in range(len(parts))]
    counters = []
    for part in parts:
        info = debian_info(part, env)
        assert topic_table(info)["/big"][0] == "std_msgs/String"
        values = bag_values(part, "/big")
        assert info["messages"] == len(values) > 0
        assert part.stat().st_size < 0.2 * 1024 * 1024 + 20_000  # the limit plus one message and index
        counters += [int(v.split(":")[0]) for v in values]
    assert counters == list(range(counters[0], counters[0] + len(counters)))


def _subscribed(env: dict[str, str]) -> list[tuple[str, list[str]]]:
    from tests.test_bag_play import system_state

    _pubs, subs = system_state(env)
    return [(str(t), list(n)) for t, n in subs]  # type: ignore[call-overload]


def test_sigterm_and_formats(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    counter = start_rospy_script(COUNTER_PUBLISHER, env, tmp_path, "counter", ["/count", "100", "1000000"])
    try:
        wait_published(env, "/count")
        recorders = {
            "term.bag": record(env, tmp_path, ["/count", "-O", "term.bag", "--lz4"]),
            "run.mcap": record(env, tmp_path, ["/count", "-O", "run.mcap"]),
            "run.db3": record(env, tmp_path, ["/count", "-O", "run", "--format", "db3"]),
        }
        wait_subscribed(env, "/count", 3)
        time.sleep(1.5)
        for proc in recorders.values():
            finish(proc, signal.SIGTERM)
    finally:
        stop(counter)
    info = debian_info(tmp_path / "term.bag", env)
    assert info["compression"] == "lz4" and topic_table(info)["/count"][0] == "std_msgs/Int32"
    for name in ("term.bag", "run.mcap", "run.db3"):
        path = tmp_path / name
        assert path.is_file() and not path.with_name(name + ".active").exists()
        ours = json.loads(rostool(["bag", "info", "--json", str(path)], env).stdout)
        topic = next(t for t in ours["topics"] if t["name"] == "/count")
        expected_type = "std_msgs/Int32" if name.endswith(".bag") else "std_msgs/msg/Int32"
        assert topic["type"] == expected_type and topic["count"] >= 100
        echoed = rostool(["bag", "echo", str(path), "/count", "--json"], env)
        values = [json.loads(line)["data"] for line in echoed.stdout.splitlines()]
        assert len(values) == topic["count"] and values == list(range(values[0], values[0] + len(values)))


def test_kill_9_then_reindex_keeps_every_flushed_message(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    env = debian_master
    # 1. everything published long enough before the kill is recovered, exactly
    recorder = record(env, tmp_path, ["/count", "-O", "killed.bag"])
    counter = start_rospy_script(COUNTER_PUBLISHER, env, tmp_path, "counter", ["/count", "50", "100", "1"])
    try:
        assert wait_until(lambda: "DONE" in (counter.stdout.readline() if counter.stdout else ""), 30)
        time.sleep(1.0)
        recorder.kill()
        recorder.wait(10)
    finally:
        stop(counter)
    active = tmp_path / "killed.bag.active"
    assert active.exists() and not (tmp_path / "killed.bag").exists()
    reindexed = rostool(["bag", "reindex", str(active)], env)
    assert reindexed.returncode == 0, reindexed.stderr
    recovered = active.rename(tmp_path / "killed.bag")
    assert [int(v) for v in bag_values(recovered, "/count")] == list(range(100))
    assert debian_info(recovered, env)["messages"] == 100

    # 2. killed mid-stream: no gap, and nothing published more than 0.5 s before the kill is missing
    recorder = record(env, tmp_path, ["/count", "-O", "mid.bag"])
    counter = Watched(
        start_rospy_script(COUNTER_PUBLISHER, env, tmp_path, "counter2", ["/count", "200", "100000", "1"])
    )
    try:
        # killed once 300 are out (1.5 s at 200 Hz): the recorder got the first ones over a second before
        counter.wait_for(lambda out: out.count("\n") >= 300, 30)
        killed_at = time.time()
        recorder.kill()
        recorder.wait(10)
    finally:
        published, _err = counter.stop()
    active = tmp_path / "mid.bag.active"
    assert rostool(["bag", "reindex", str(active)], env).returncode == 0
    recovered = active.rename(tmp_path / "mid.bag")
    values = [int(v) for v in bag_values(recovered, "/count")]
    assert values == list(range(len(values))) and len(values) > 100
    sent = [(t, int(v)) for t, v in timed_values(published)]
    must_have = max(v for t, v in sent if t < killed_at - 0.5)
    assert values[-1] >= must_have
    info = debian_info(recovered, env)
    assert info["messages"] == len(values)


def test_book_w9_temperature_workflow(debian_master: dict[str, str], tmp_path: Path) -> None:
    """Book chapter 16 (W9) with rostool: record -a, param set mid-recording, info, play, echo, -r 2."""
    env = debian_master
    publisher = start_rospy_script(TEMPERATURE_PUBLISHER, env, tmp_path, "temperature_publisher", ["20"])
    subscriber = start_rospy_script(TEMPERATURE_SUBSCRIBER, env, tmp_path, "temperature_subscriber")
    try:
        wait_published(env, "/temperature_status")
        recorder = record(env, tmp_path, ["-a", "-O", "test.bag"])
        wait_recording(env, "/temperature_status")
        time.sleep(1.5)
        assert rostool(["param", "set", "/threshold_temp", "35.0"], env).returncode == 0
        time.sleep(2.0)
        finish(recorder)
    finally:
        stop(publisher)
        stop(subscriber)
    bag = tmp_path / "test.bag"
    info = rostool(["bag", "info", str(bag)], env)
    assert info.returncode == 0, info.stderr
    assert re.search(r"/current_temperature\s+\d+ msgs\s+: std_msgs/Float32", info.stdout), info.stdout
    assert re.search(r"/temperature_status\s+\d+ msgs\s+: std_msgs/String", info.stdout), info.stdout
    statuses = bag_values(bag, "/temperature_status")
    thresholds = [s.split(",")[1] for s in statuses]
    assert "30.0" in thresholds and "35.0" in thresholds
    assert thresholds == sorted(thresholds)  # 30.0 until the change, 35.0 after it
    assert all(s.endswith(",ALERT") == (float(s.split(",")[0]) > float(s.split(",")[1])) for s in statuses)
    # play it back (the live nodes are stopped) to `rostool topic echo`
    echo = rostool_popen(["topic", "echo", "/temperature_status"], env)
    try:
        wait_subscribed(env, "/temperature_status")
        played = rostool(["bag", "play", "-d", "1", str(bag)], env, timeout=60)
        assert played.returncode == 0, played.stderr
        time.sleep(0.5)
    finally:
        out, _err = stop(echo)
    assert echo_strings(out) == statuses
    # -r 2.0: the same messages in half the time
    sub = start_rospy_script(
        TIMED_SUBSCRIBER, env, tmp_path, "timed", ["/temperature_status", "std_msgs/String"]
    )
    try:
        wait_subscribed(env, "/temperature_status")
        fast = rostool(["bag", "play", "-d", "1", "-r", "2.0", str(bag)], env, timeout=60)
        assert fast.returncode == 0, fast.stderr
        time.sleep(0.5)
    finally:
        received, _err = stop(sub)
    rows = timed_values(received)
    assert [v for _t, v in rows] == statuses
    recorded_span = _stamp_span(bag, "/temperature_status")
    assert 0.4 < (rows[-1][0] - rows[0][0]) / recorded_span < 0.6


def _stamp_span(bag: Path, topic: str) -> float:
    from rosbags.rosbag1 import Reader

    with Reader(bag) as reader:
        stamps = [t for c, t, _d in reader.messages() if c.topic == topic]
    return (stamps[-1] - stamps[0]) / 1e9


def test_bad_output_is_one_line(ros_env: dict[str, str], tmp_path: Path) -> None:
    env = ros_env  # no master: every check happens before the graph is needed
    existing = tmp_path / "exists.bag"
    existing.write_bytes(b"precious")
    refused = rostool(["bag", "record", "-a", "-O", str(existing)], env)
    assert refused.returncode == 1 and refused.stderr.count("\n") == 1 and "--force" in refused.stderr
    assert existing.read_bytes() == b"precious"
    no_dir = rostool(["bag", "record", "-a", "-O", str(tmp_path / "nowhere" / "x.bag")], env)
    assert no_dir.returncode == 1 and "does not exist" in no_dir.stderr and no_dir.stderr.count("\n") == 1
    not_dir = rostool(["bag", "record", "-a", "-O", str(existing / "x.bag")], env)
    assert not_dir.returncode == 1 and "not a directory" in not_dir.stderr
    nothing = rostool(["bag", "record"], env)
    assert nothing.returncode == 1 and "-a" in nothing.stderr
    both = rostool(["bag", "record", "-a", "-O", "a.bag", "-o", "b"], env)
    assert both.returncode == 1
    for result in (refused, no_dir, not_dir, nothing, both):
        no_traceback(result)


def test_force_and_disk_full(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    existing = tmp_path / "again.bag"
    existing.write_bytes(b"old")
    forced = rostool(["bag", "record", "/none", "-O", str(existing), "--force", "--duration", "0.3"], env)
    assert forced.returncode == 0, forced.stderr
    assert debian_info(existing, env)["version"] == 2.0

    def small_files() -> None:  # a full disk, as the file size limit makes writes fail with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (400_000, 400_000))

    big = start_rospy_script(BIG_PUBLISHER, env, tmp_path, "big", ["/big", "50", "20000"])
    try:
        wait_published(env, "/big")
        recorder = record(env, tmp_path, ["/big", "-O", "full.bag"], preexec_fn=small_files)
        _out, err = recorder.communicate(timeout=30)  # stops by itself when the disk is full
    finally:
        stop(big)
    assert recorder.returncode == 1 and err.count("\n") == 1, err
    assert "File too large" in err and "full.bag" in err and "Traceback" not in err
    info = debian_info(tmp_path / "full.bag", env)
    values = bag_values(tmp_path / "full.bag", "/big")
    assert info["messages"] == len(values) > 5
    counters = [int(v.split(":")[0]) for v in values]
    assert counters == list(range(counters[0], counters[0] + len(counters)))
    assert nodes_on(env, "/big") == []  # unsubscribed


def test_limit_max_splits_and_node(debian_master: dict[str, str], tmp_path: Path) -> None:
    """rosbag's --limit (ends by itself), --max-splits (oldest files deleted) and --node (the node's
    subscriptions), checked with Debian's rosbag."""
    env = debian_master
    listener_script = (
        "import rospy\nfrom std_msgs.msg import String\nrospy.init_node('listener')\n"
        "rospy.Subscriber('hello_world', String, lambda m: None)\nrospy.spin()\n"
    )
    hello = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    listener = start_rospy_script(listener_script, env, tmp_path, "listener")
    counter = start_rospy_script(COUNTER_PUBLISHER, env, tmp_path, "counter", ["/count", "50", "100000"])
    try:
        wait_published(env, "/hello_world")
        wait_published(env, "/count")
        wait_subscribed(env, "/hello_world")
        limited = rostool(["bag", "record", "/count", "/hello_world", "-l", "3", "-O", "limited.bag"], env,
                          cwd=tmp_path, timeout=20)  # fmt: skip
        assert limited.returncode == 0, limited.stderr
        info = debian_info(tmp_path / "limited.bag", env)
        assert {t["topic"]: t["messages"] for t in info["topics"]} == {"/count": 3, "/hello_world": 3}

        splitting = record(env, tmp_path, ["/count", "-O", "part.bag", "--split", "--duration", "0.4",
                                           "--max-splits", "2"])  # fmt: skip
        time.sleep(3.0)
        _out, err = finish(splitting)
        assert splitting.returncode == 0, err
        parts = sorted(tmp_path.glob("part_*.bag"))
        assert len(parts) == 2 and "--max-splits removed" in err, (parts, err)
        assert parts[0].name != "part_0.bag"  # the oldest went first
        for part in parts:
            assert debian_info(part, env)["topics"][0]["topic"] == "/count"

        node = rostool(["bag", "record", "--node", "/listener", "-O", "node.bag", "--duration", "1.5"], env,
                       cwd=tmp_path)  # fmt: skip
        assert node.returncode == 0, node.stderr
        topics = {t["topic"] for t in debian_info(tmp_path / "node.bag", env)["topics"]}
        assert topics == {"/hello_world"}  # what /listener subscribes to, not /count or /rosout
    finally:
        for proc in (counter, hello, listener):
            stop(proc)
