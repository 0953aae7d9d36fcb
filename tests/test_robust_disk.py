"""A disk that fills up while `bag record` closes its bag (issue 27): every message that reached the disk
survives, the exit is non-zero with one line naming `rostool bag reindex`, and that command makes the
leftover readable again once there is room.

The recording stops (a real rospy publisher has sent all it will) before the test fills the small tmpfs
to its last byte, so the failure is in closing (index, metadata), never in writing the messages.
"""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
from pathlib import Path

import pytest

from tests import test_full_disk
from tests.support import debian, rostool, rostool_popen, start_rospy_script, stop, wait_until
from tests.test_bag_play import wait_published
from tests.test_full_disk import _one_full_line, _values

small_disk = test_full_disk.small_disk  # the fixture: a fresh 2 MB tmpfs

COUNT = 1500
# Publishes COUNT numbered strings once a subscriber is connected, then says so and stays (a publisher
# leaving would not change the bag, but staying keeps the recorder's link the only variable).
COUNTED_PUBLISHER = """
import sys
import rospy
from std_msgs.msg import String
topic, count = sys.argv[1], int(sys.argv[2])
rospy.init_node('counted', anonymous=True)
pub = rospy.Publisher(topic, String, queue_size=count)
while pub.get_num_connections() == 0 and not rospy.is_shutdown():
    rospy.sleep(0.05)
rate = rospy.Rate(1000)
for i in range(count):
    pub.publish(String(data='%d:' % i + 'x' * 100))
    rate.sleep()
print('done', flush=True)
rospy.spin()
"""


def _on_disk(fmt: str, active: Path) -> int:
    """How many messages of the running recording reached the disk (read without disturbing it)."""
    if fmt == "bag":  # streamed records of 46 header bytes + 4 + ~104 payload bytes each
        return (active.stat().st_size - 4109) // 154 if active.exists() else 0
    if fmt == "db3":
        db = active / f"{active.name}.db3"
        if not db.exists():
            return 0
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as conn:
            try:
                return int(conn.execute("select count(*) from messages").fetchone()[0])
            except sqlite3.Error:
                return 0
    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    data = active / f"{active.name}.mcap"
    count = 0
    if data.exists():
        try:
            with data.open("rb") as stream:
                for record in StreamReader(stream).records:
                    count += isinstance(record, Message)
        except Exception:  # the file ends mid-record: what came before counts
            pass
    return count


def _fill(disk: Path) -> None:
    fd = os.open(disk / "filler", os.O_WRONLY | os.O_CREAT)
    try:
        while True:
            os.write(fd, bytes(4096))
    except OSError:
        pass
    finally:
        os.close(fd)
    try:  # and the last bytes, smaller than a page
        with (disk / "filler2").open("wb", buffering=0) as tail:
            while True:
                tail.write(b"x")
    except OSError:
        pass


@pytest.mark.parametrize("fmt", ["bag", "db3", "mcap"])
def test_disk_full_while_closing_keeps_every_message(
    debian_master: dict[str, str], tmp_path: Path, small_disk: Path, fmt: str
) -> None:
    env = debian_master
    publisher = start_rospy_script(COUNTED_PUBLISHER, env, tmp_path, "counted", ["/counted", str(COUNT)])
    target = small_disk / f"rec.{fmt}"
    active = small_disk / f"rec.{fmt}.active"
    recorder = rostool_popen(["bag", "record", "/counted", "-O", str(target)], env)
    try:
        wait_published(env, "/counted")
        assert publisher.stdout is not None
        assert publisher.stdout.readline().strip() == "done"
        assert wait_until(lambda: _on_disk(fmt, active) >= COUNT, 30), _on_disk(fmt, active)
        _fill(small_disk)
        recorder.send_signal(signal.SIGINT)
        _out, err = recorder.communicate(timeout=30)
    finally:
        if recorder.poll() is None:
            recorder.kill()
        stop(publisher)
    assert recorder.returncode == 1, err
    _one_full_line(err)
    assert "rostool bag reindex" in err, err
    assert not target.exists() and active.exists()
    saved = tmp_path / (active.name if active.is_dir() else target.name)  # somewhere with room
    if active.is_dir():
        shutil.copytree(active, saved)
    else:
        shutil.copy(active, saved)
    done = rostool(["bag", "reindex", str(saved)], env, timeout=60)
    assert done.returncode == 0, done.stderr
    assert _values(saved) == list(range(COUNT))
    if fmt == "bag":  # and Debian's rosbag reads the repaired bag
        info = debian(["rosbag", "info", "--yaml", str(saved)], env)
        assert info.returncode == 0 and f"messages: {COUNT}" in info.stdout, info.stdout + info.stderr


def test_no_room_for_the_index_of_a_bag_never_cuts_messages(tmp_path: Path, small_disk: Path) -> None:
    """The writer alone: a streamed chunk fits, its index does not; the file keeps every message."""
    from rostool.bag.ros1_writer import BagWriter, WriteFailed

    path = small_disk / "w.bag"
    writer = BagWriter(path)
    header = {"topic": "/t", "type": "std_msgs/String", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1"}
    conn = writer.connection({**header, "message_definition": "string data\n", "callerid": "/w"})
    for i in range(COUNT):
        text = f"{i}:".encode() + b"y" * 100
        writer.write(conn, 1_700_000_000_000_000_000 + i * 1000, len(text).to_bytes(4, "little") + text)
    writer.flush()
    _fill(small_disk)
    with pytest.raises(WriteFailed):
        writer.close()
    saved = tmp_path / "w.bag"
    shutil.copy(path, saved)
    assert rostool(["bag", "reindex", str(saved)], dict(os.environ), timeout=60).returncode == 0
    assert _values(saved) == list(range(COUNT))
