"""`rostool bag play` into a real ROS 1 graph: Debian's rosmaster, rospy subscribers and `rostopic echo`."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Callable
from pathlib import Path

from tests.peers import HELLO_PUBLISHER
from tests.support import (
    TESTDATA,
    Watched,
    debian,
    debian_popen,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
    wait_until,
)

# Prints "WALLTIME VALUE" for each message; VALUE is the `data` field, or secs.nsecs of a Clock.
TIMED_SUBSCRIBER = """
import sys, time
import rospy
import roslib.message
topic, type_name = sys.argv[1], sys.argv[2]
cls = roslib.message.get_message_class(type_name)
rospy.init_node('timed_sub', anonymous=True)
def on(msg):
    now = time.time()
    if hasattr(msg, 'clock'):
        value = '%d.%09d' % (msg.clock.secs, msg.clock.nsecs)
    else:
        value = str(msg.data)
    print('%.6f %s' % (now, value), flush=True)
rospy.Subscriber(topic, cls, on, queue_size=10000)
rospy.spin()
"""

# Publishes Int32 0..COUNT-1 on TOPIC at RATE Hz, printing "WALLTIME VALUE" after each, then "DONE".
COUNTER_PUBLISHER = """
import sys, time
import rospy
from std_msgs.msg import Int32
topic, rate, count = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
rospy.init_node('counter', anonymous=True)
pub = rospy.Publisher(topic, Int32, queue_size=1000)
while pub.get_num_connections() < int(sys.argv[4] if len(sys.argv) > 4 else 0):
    time.sleep(0.01)
time.sleep(0.2)
period = rospy.Rate(rate)
for i in range(count):
    pub.publish(Int32(data=i))
    print('%.6f %d' % (time.time(), i), flush=True)
    period.sleep()
print('DONE', flush=True)
rospy.spin()
"""

T0 = 1_700_000_000_000_000_000


# -- helpers shared with test_bag_record ---------------------------------------------------------
def system_state(env: dict[str, str]) -> tuple[list[list[object]], list[list[object]]]:
    proxy = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    _code, _msg, (pubs, subs, _srvs) = proxy.getSystemState("/test")  # type: ignore[misc]
    return pubs, subs


def nodes_on(env: dict[str, str], topic: str, kind: str = "sub") -> list[str]:
    pubs, subs = system_state(env)
    for name, nodes in pubs if kind == "pub" else subs:
        if name == topic:
            return list(nodes)  # type: ignore[call-overload]
    return []


def wait_subscribed(env: dict[str, str], topic: str, count: int = 1) -> None:
    assert wait_until(lambda: len(nodes_on(env, topic)) >= count, 20), f"nobody subscribed to {topic}"


def wait_published(env: dict[str, str], topic: str) -> None:
    assert wait_until(lambda: bool(nodes_on(env, topic, "pub")), 20), f"nobody publishes {topic}"


def echo_strings(text: str) -> list[str]:
    """The `data` values of `rostopic echo` output (strings unquoted)."""
    return [m.strip('"') for m in re.findall(r"^data: (.*)$", text, re.M)]


def timed_values(text: str) -> list[tuple[float, str]]:
    rows = []
    for line in text.splitlines():
        parts = line.split(" ", 1)
        if len(parts) == 2 and re.fullmatch(r"\d+\.\d+", parts[0]):
            rows.append((float(parts[0]), parts[1]))
    return rows


def bag_values(path: Path, topic: str) -> list[str]:
    """The `data` values on `topic`, read with rosbags' own reader (independent of ours)."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([path], default_typestore=get_typestore(Stores.ROS1_NOETIC)) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [str(reader.deserialize(data, c.msgtype).data) for c, _t, data in reader.messages(conns)]


def write_int_bag(
    path: Path, count: int, period_ns: int, topic: str = "/numbers", latching: int | None = None
) -> Path:
    """A ROS 1 bag of std_msgs/Int32 0..count-1, `period_ns` apart from T0 (rosbags' writer)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    cls = store.types["std_msgs/msg/Int32"]
    with Writer(path) as writer:
        conn = writer.add_connection(topic, "std_msgs/msg/Int32", typestore=store, latching=latching)
        for i in range(count):
            writer.write(conn, T0 + i * period_ns, store.serialize_ros1(cls(data=i), "std_msgs/msg/Int32"))
    return path


def write_rows_bag(path: Path, rows: list[tuple[str, float, int]]) -> Path:
    """A ROS 1 bag of std_msgs/Int32 messages, each (topic, seconds after T0, value)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    cls = store.types["std_msgs/msg/Int32"]
    with Writer(path) as writer:
        conns = {}
        for topic, _t, _v in rows:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, "std_msgs/msg/Int32", typestore=store)
        for topic, seconds, value in sorted(rows, key=lambda row: row[1]):
            data = store.serialize_ros1(cls(data=value), "std_msgs/msg/Int32")
            writer.write(conns[topic], T0 + round(seconds * 1e9), data)
    return path


# /numbers 0..9: 0.1 s apart, with 20 s without any message between 4 and 5
GAP_OFFSETS = [0.0, 0.1, 0.2, 0.3, 0.4, 20.4, 20.5, 20.6, 20.7, 20.8]


def gap_bag(tmp_path: Path) -> Path:
    return write_rows_bag(tmp_path / "gap.bag", [("/numbers", t, i) for i, t in enumerate(GAP_OFFSETS)])


def no_traceback(result: subprocess.CompletedProcess[str] | tuple[str, str]) -> None:
    text = result.stderr if isinstance(result, subprocess.CompletedProcess) else result[1]
    assert "Traceback" not in text, text


class TimedSubscriber:
    """A rospy subscriber (TIMED_SUBSCRIBER) on one topic that a test's plays share: each play's messages
    are the lines printed since that play began, and `close` checks nothing came outside a play."""

    def __init__(self, env: dict[str, str], tmp_path: Path, topic: str, type_name: str) -> None:
        self.env = env
        self.lines_played = 0
        proc = start_rospy_script(
            TIMED_SUBSCRIBER, env, tmp_path, f"sub{time.monotonic_ns()}", [topic, type_name]
        )
        self.watched = Watched(proc)
        wait_subscribed(env, topic)

    def play(
        self,
        args: list[str],
        until: Callable[[list[tuple[float, str]]], bool],
        wait: tuple[str, ...] = ("--wait-for-subscribers",),
    ) -> tuple[subprocess.CompletedProcess[str], list[tuple[float, str]]]:
        """Run `rostool bag play ARGS`; what this subscriber received from it, once `until(received)`
        holds (or 10 s passed: the caller's assertion then says what is missing)."""
        before = len(timed_values(self.watched.stdout))
        played = rostool(["bag", "play", *wait, *args], self.env, timeout=60)
        assert played.returncode == 0, played.stderr
        no_traceback(played)
        self.watched.wait_for(lambda out: until(timed_values(out)[before:]), 10)
        received = timed_values(self.watched.stdout)[before:]
        self.lines_played += len(received)
        return played, received

    def close(self) -> None:
        """Stops the subscriber: every message it printed came during a play (none after it was read)."""
        out, _err = self.watched.stop()
        assert len(timed_values(out)) == self.lines_played, out


def count(n: int) -> Callable[[list[tuple[float, str]]], bool]:
    return lambda received: len(received) >= n


def play_into(
    env: dict[str, str],
    tmp_path: Path,
    topic: str,
    type_name: str,
    args: list[str],
    until: Callable[[list[tuple[float, str]]], bool],
    wait: tuple[str, ...] = ("--wait-for-subscribers",),
) -> tuple[subprocess.CompletedProcess[str], list[tuple[float, str]]]:
    """Start a rospy subscriber on `topic`, run `rostool bag play ARGS`, return what it received."""
    sub = TimedSubscriber(env, tmp_path, topic, type_name)
    try:
        return sub.play(args, until, wait)
    finally:
        sub.close()


# -- tests ---------------------------------------------------------------------------------------
def test_bag_from_debian_rosbag_record_plays_to_rostopic_echo(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    env = debian_master
    bag = tmp_path / "theirs.bag"
    pub = start_rospy_script(HELLO_PUBLISHER, env, tmp_path, "hello")
    try:
        wait_published(env, "/hello_world")
        recorder = debian_popen(["rosbag", "record", "-O", str(bag), "/hello_world"], env)
        wait_until(lambda: bag.with_name("theirs.bag.active").exists() or bag.exists(), 20)
        time.sleep(2.5)
        stop(recorder, timeout=10)
    finally:
        stop(pub)
    expected = bag_values(bag, "/hello_world")
    assert len(expected) >= 5 and all(v.startswith("Hello_World_") for v in expected)
    echo = Watched(debian_popen(["rostopic", "echo", "/hello_world"], env))
    try:
        wait_subscribed(env, "/hello_world")
        played = rostool(["bag", "play", "--wait-for-subscribers", "-r", "4", str(bag)], env)
        assert played.returncode == 0, played.stderr
        assert played.stderr == ""  # not a terminal: no status line
        echo.wait_for(lambda out: len(echo_strings(out)) >= len(expected), 10)
    finally:
        out, _err = echo.stop()
    assert echo_strings(out) == expected
    # the publisher is gone from the master once play has ended
    assert nodes_on(env, "/hello_world", "pub") == []


def test_rate_loop_window_remap_and_clock(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    bag = write_int_bag(tmp_path / "numbers.bag", count=41, period_ns=50_000_000)  # 2 s at 20 Hz
    numbers = TimedSubscriber(env, tmp_path, "/numbers", "std_msgs/Int32")  # one for the three plays
    try:
        _played, normal = numbers.play([str(bag)], count(41))
        assert [v for _t, v in normal] == [str(i) for i in range(41)]
        _played, fast = numbers.play(["-r", "2", str(bag)], count(41))
        assert [v for _t, v in fast] == [str(i) for i in range(41)]
        span_normal, span_fast = normal[-1][0] - normal[0][0], fast[-1][0] - fast[0][0]
        assert 1.8 < span_normal < 2.6, span_normal
        assert 0.4 < span_fast / span_normal < 0.6, (span_fast, span_normal)
        # -s/-u: exactly the messages stamped within [start + 0.5 s, start + 0.5 s + 0.3 s]
        _played, window = numbers.play(["-s", "0.5", "-u", "0.3", str(bag)], count(7))
        assert [v for _t, v in window] == [str(i) for i in range(10, 17)]
    finally:
        numbers.close()
    # remapping, as an option and as a ROS-style argument
    renamed_sub = TimedSubscriber(env, tmp_path, "/renamed", "std_msgs/Int32")
    try:
        for remap in (["--remap", "/numbers:=/renamed"], ["/numbers:=/renamed"]):
            _played, renamed = renamed_sub.play(["-r", "10", str(bag), *remap], count(41))
            assert [v for _t, v in renamed] == [str(i) for i in range(41)]
    finally:
        renamed_sub.close()
    # --clock: /clock carries bag times, every message's stamp among them, never going back
    last = f"{(T0 + 40 * 50_000_000) // 10**9}.{(T0 + 40 * 50_000_000) % 10**9:09d}"
    _played, clock = play_into(
        env, tmp_path, "/clock", "rosgraph_msgs/Clock", ["--clock", str(bag)],
        lambda received: any(v == last for _t, v in received), wait=("-d", "1.5"),
    )  # fmt: skip
    stamps = [int(v.split(".")[0]) * 1_000_000_000 + int(v.split(".")[1]) for _t, v in clock]
    assert len(stamps) > 41 + 100  # 100 Hz during 2 s, plus one per message
    assert all(T0 - 1000 <= s <= T0 + 2_000_000_000 + 1000 for s in stamps)
    assert stamps == sorted(stamps)
    message_stamps = {T0 + i * 50_000_000 for i in range(41)}
    assert message_stamps <= set(stamps)


def test_loop_repeats_and_ctrl_c_unregisters(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    bag = write_int_bag(tmp_path / "short.bag", count=5, period_ns=20_000_000)
    sub = Watched(start_rospy_script(TIMED_SUBSCRIBER, env, tmp_path, "sub", ["/numbers", "std_msgs/Int32"]))
    try:
        wait_subscribed(env, "/numbers")
        player = rostool_popen(["bag", "play", "-l", "--wait-for-subscribers", str(bag)], env)
        wait_published(env, "/numbers")
        sub.wait_for(lambda out: len(timed_values(out)) > 10, 20)  # the bag more than twice
        player.send_signal(signal.SIGINT)
        out, err = player.communicate(timeout=10)
        assert player.returncode == 130, err
        assert "Traceback" not in err and out == ""
        assert wait_until(lambda: nodes_on(env, "/numbers", "pub") == [], 5)
    finally:
        received, _err = sub.stop()
    values = [v for _t, v in timed_values(received)]
    assert len(values) > 10  # the bag holds 5
    assert values[:10] == [str(i % 5) for i in range(10)]


def test_latched_topic_reaches_a_late_subscriber(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    bag = write_int_bag(tmp_path / "latched.bag", count=3, period_ns=10_000_000, topic="/map", latching=1)
    player = rostool_popen(["bag", "play", "-k", "-d", "0", str(bag)], env)
    try:
        wait_published(env, "/map")
        time.sleep(1.0)  # played and done; the latched publisher stays (-k)
        late = debian(["rostopic", "echo", "-n", "1", "/map"], env, timeout=20)
        assert late.stdout == "data: 2\n---\n", late.stderr
    finally:
        stop(player)


def test_ros2_bag_plays_into_ros1(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    echo = Watched(debian_popen(["rostopic", "echo", "/topic"], env))
    try:
        # rostopic echo subscribes once the topic has a publisher; play waits for it
        bag = TESTDATA / "ros2" / "talker_mcap"
        played = rostool(["bag", "play", "--wait-for-subscribers", "-r", "5", str(bag)], env)
        assert played.returncode == 0, played.stderr
        echo.wait_for(lambda out: len(echo_strings(out)) >= 10, 10)
    finally:
        out, _err = echo.stop()
    assert echo_strings(out) == [f"Hello, world! {i}" for i in range(10)]
    # the Log and ParameterEvent topics have no ROS 1 type: skipped, each with one warning line
    warnings = played.stderr.splitlines()
    assert len(warnings) == 2 and all(w.startswith("rostool: warning: skipping /") for w in warnings)
    assert "rcl_interfaces/msg/Log" in played.stderr
    # a single .db3 file too, and only a type without ROS 1 equivalent is an error
    only_log = rostool(["bag", "play", str(TESTDATA / "ros2/talker_sqlite3"), "--topics", "/rosout"], env)
    assert only_log.returncode == 1 and len(only_log.stderr.splitlines()) == 1
    assert "nothing to play in ROS 1" in only_log.stderr and "rcl_interfaces/msg/Log" in only_log.stderr


def test_bad_input_is_one_line(ros_env: dict[str, str], tmp_path: Path) -> None:
    env = ros_env  # no master is running
    missing = rostool(["bag", "play", str(tmp_path / "missing.bag")], env)
    assert missing.returncode == 1 and missing.stderr.count("\n") == 1 and "no such file" in missing.stderr
    text = tmp_path / "notes.txt"
    text.write_text("hello\n")
    not_bag = rostool(["bag", "play", str(text)], env)
    assert not_bag.returncode == 1 and "not a bag" in not_bag.stderr and not_bag.stderr.count("\n") == 1
    bag = write_int_bag(tmp_path / "n.bag", count=2, period_ns=1000)
    no_master = rostool(["bag", "play", str(bag)], env)
    assert no_master.returncode == 1 and "master" in no_master.stderr and no_master.stderr.count("\n") == 1
    unknown = rostool(["bag", "play", str(bag), "--topics", "/nope"], env)
    assert unknown.returncode == 1 and "/nope" in unknown.stderr
    bad_remap = rostool(["bag", "play", str(bag), "--remap", "/a"], env)
    assert bad_remap.returncode == 1 and "FROM:=TO" in bad_remap.stderr
    for result in (missing, not_bag, no_master, unknown, bad_remap):
        no_traceback(result)


class PtyPlay:
    """`rostool bag play ARGS` in a pseudo-terminal that is its controlling terminal and stdin/out/err."""

    def __init__(self, args: list[str], env: dict[str, str]) -> None:
        import pty
        import termios

        self.master_fd, self.slave_fd = pty.openpty()
        self.mode = termios.tcgetattr(self.slave_fd)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "rostool", "bag", "play", *args],
            env=env,
            stdin=self.slave_fd,
            stdout=self.slave_fd,
            stderr=self.slave_fd,
            start_new_session=True,
            preexec_fn=lambda: __import__("fcntl").ioctl(0, termios.TIOCSCTTY, 0),
        )
        self.output = b""

    def __enter__(self) -> PtyPlay:
        return self

    def __exit__(self, *_exc: object) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        os.close(self.master_fd)
        os.close(self.slave_fd)

    def read_until(self, pattern: bytes, timeout: float) -> bool:
        import select

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            ready, _w, _x = select.select([self.master_fd], [], [], 0.05)
            if ready:
                try:
                    self.output += os.read(self.master_fd, 4096)
                except OSError:
                    return pattern in self.output
            if pattern in self.output:
                return True
        return pattern in self.output

    def press(self, key: bytes) -> None:
        os.write(self.master_fd, key)

    def mode_restored(self) -> bool:
        import termios

        return bool(termios.tcgetattr(self.slave_fd) == self.mode)


def test_terminal_status_line_and_space_pauses(debian_master: dict[str, str], tmp_path: Path) -> None:
    """In a terminal: rosbag's status line, space pauses and resumes, the terminal mode is restored."""
    bag = write_int_bag(tmp_path / "numbers.bag", count=21, period_ns=50_000_000)  # 1 s
    with PtyPlay(["-d", "0", str(bag)], debian_master) as play:
        assert play.read_until(b"Hit space to toggle paused", 20), play.output
        play.press(b" ")
        assert play.read_until(b"[PAUSED ]", 5), play.output
        time.sleep(1.5)  # paused longer than the whole bag lasts
        assert play.proc.poll() is None
        play.press(b" ")
        assert play.read_until(b"Done.", 10), play.output
        assert play.proc.wait(10) == 0
        assert b"[RUNNING]  Bag Time: 1700000000." in play.output
        assert re.search(rb"Duration: 1\.000000 / 1\.000000", play.output) or b"/ 1.000000" in play.output
        assert play.mode_restored()


def test_pause_topics_pause_before_their_message_until_space(
    debian_master: dict[str, str], tmp_path: Path
) -> None:
    env = debian_master
    rows = [("/numbers", i * 0.05, i) for i in range(20)] + [("/pause_here", 0.525, 100)]
    bag = write_rows_bag(tmp_path / "pause.bag", rows)
    subs = {
        topic: Watched(
            start_rospy_script(TIMED_SUBSCRIBER, env, tmp_path, f"sub{n}", [topic, "std_msgs/Int32"])
        )
        for n, topic in enumerate(("/numbers", "/pause_here"))
    }
    try:
        for topic in subs:
            wait_subscribed(env, topic)
        args = ["--wait-for-subscribers", "-d", "0", str(bag), "--pause-topics", "/pause_here"]
        with PtyPlay(args, env) as play:
            assert play.read_until(b"Hit space to toggle paused", 20), play.output
            assert play.read_until(b"[PAUSED ]", 5), play.output  # no key pressed: /pause_here paused it
            time.sleep(1.5)  # longer than the rest of the bag
            assert play.proc.poll() is None
            resumed = time.time()
            play.press(b" ")
            assert play.read_until(b"Done.", 10), play.output
            assert play.proc.wait(10) == 0
            assert b"Bag Time: 1700000000.5" in play.output  # paused at the time of the last message before
            assert play.mode_restored()
        for topic, expected in (("/numbers", 20), ("/pause_here", 1)):
            subs[topic].wait_for(lambda out, n=expected: len(timed_values(out)) >= n, 10)
    finally:
        received = {topic: timed_values(sub.stop()[0]) for topic, sub in subs.items()}
    numbers = received["/numbers"]
    assert [v for _t, v in numbers] == [str(i) for i in range(20)]
    assert all(t < resumed for t, v in numbers if int(v) <= 10)  # stamped before /pause_here's message
    assert all(t > resumed for t, v in numbers if int(v) >= 11)
    assert [v for _t, v in received["/pause_here"]] == ["100"]  # held while paused, then published
    assert received["/pause_here"][0][0] > resumed


def test_pause_topics_without_a_terminal_is_one_line(debian_master: dict[str, str], tmp_path: Path) -> None:
    """rosbag would stay paused for ever at the first such message without a terminal: an error instead."""
    env = debian_master
    bag = write_int_bag(tmp_path / "n.bag", count=3, period_ns=10_000_000)
    no_tty = rostool(["bag", "play", str(bag), "--pause-topics", "/numbers"], env, input="")
    assert no_tty.returncode == 1 and no_tty.stderr.count("\n") == 1, no_tty.stderr
    assert "--pause-topics needs a terminal on stdin" in no_tty.stderr
    # names after the bags go to --pause-topics; they must be bag topics (before --prefix and --remap)
    args = ["-p", "/pre", str(bag), "--pause-topics", "/numbers", "/pre/numbers"]
    unknown = rostool(["bag", "play", *args], env)
    assert unknown.returncode == 1 and unknown.stderr.count("\n") == 1, unknown.stderr
    assert "--pause-topics /pre/numbers: not played" in unknown.stderr
    for result in (no_tty, unknown):
        no_traceback(result)


def test_skip_empty_jumps_over_gaps_with_clock(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    bag = gap_bag(tmp_path)
    numbers = TimedSubscriber(env, tmp_path, "/numbers", "std_msgs/Int32")  # one for both plays
    try:
        _played, got = numbers.play(["--skip-empty", "1", str(bag)], count(10))
        assert [v for _t, v in got] == [str(i) for i in range(10)]
        assert got[-1][0] - got[0][0] < 3.0, got  # 0.8 s of messages around the skipped 20 s
        assert got[5][0] - got[4][0] < 0.5, got
        # a gap shorter than SEC is played as recorded: 20.8 s at -r 20
        _played, kept = numbers.play(["-r", "20", "--skip-empty", "30", str(bag)], count(10))
        assert [v for _t, v in kept] == [str(i) for i in range(10)]
        assert kept[-1][0] - kept[0][0] > 0.8, kept
    finally:
        numbers.close()
    # /clock follows the bag time: it jumps with the schedule, never showing the skipped region
    clock_args = ["--clock", "--skip-empty", "1", str(bag)]
    last = f"{T0 // 10**9 + 20}.800000000"  # the last message's stamp (GAP_OFFSETS)
    _played, clock = play_into(
        env, tmp_path, "/clock", "rosgraph_msgs/Clock", clock_args,
        lambda received: any(v == last for _t, v in received), wait=("-d", "1.5"),
    )  # fmt: skip
    stamps = [int(v.split(".")[0]) * 1_000_000_000 + int(v.split(".")[1]) for _t, v in clock]
    assert stamps == sorted(stamps)
    assert {T0 + round(t * 1e9) for t in GAP_OFFSETS} <= set(stamps)
    assert not [s for s in stamps if T0 + 500_000_000 < s < T0 + 20_400_000_000]


def test_prefix_then_remap_as_rosbag(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    bag = write_int_bag(tmp_path / "numbers.bag", count=11, period_ns=20_000_000)
    echo = Watched(debian_popen(["rostopic", "echo", "/pre/numbers"], env))
    try:
        # a remapping of the bag's own name does not apply: rosbag remaps the prefixed name
        args = ["--wait-for-subscribers", "-p", "/pre", str(bag), "/numbers:=/elsewhere"]
        played = rostool(["bag", "play", *args], env)
        assert played.returncode == 0, played.stderr
        echo.wait_for(lambda out: len(echo_strings(out)) >= 11, 10)
    finally:
        out, _err = echo.stop()
    assert echo_strings(out) == [str(i) for i in range(11)]
    # a relative prefix, and a remapping of the prefixed name
    remap = ["-p", "pre", str(bag), "--remap", "/pre/numbers:=/renamed"]
    _played, renamed = play_into(env, tmp_path, "/renamed", "std_msgs/Int32", remap, count(11))
    assert [v for _t, v in renamed] == [str(i) for i in range(11)]


def test_prefix_and_skip_empty_into_ros2(tmp_path: Path) -> None:
    """The same Player plays into ROS 2: prefixed topic, the 20 s gap skipped."""
    from tests.test_ros2_graph import ros2_env, yaml_docs

    env = ros2_env()
    bag = gap_bag(tmp_path)
    # ros2 topic echo's form: with no publisher yet, the TYPE makes it subscribe and wait
    echo = rostool_popen(["topic", "echo", "/pre/numbers", "std_msgs/msg/Int32", "-n", "10"], env)
    try:
        # under ROS 2, -p is ros2 bag play's --start-paused: the prefix is spelled out
        args = ["--wait-for-subscribers", "--prefix", "/pre", "--skip-empty", "1", str(bag)]
        began = time.monotonic()
        played = rostool(["bag", "play", *args], env, timeout=60)
        elapsed = time.monotonic() - began
        out, err = echo.communicate(timeout=30)
    finally:
        if echo.poll() is None:
            stop(echo)
    assert played.returncode == 0 and played.stderr == "", played.stderr
    assert yaml_docs(out) == [f"data: {i}" for i in range(10)], err
    assert elapsed < 15, elapsed  # 20.8 s without skipping
