"""A disk that fills up under `bag record` and `bag convert`: a 2 MB tmpfs mounted by the test (as root).

The rule: one stderr line saying the disk is full (no traceback), exit 1; what was written stays readable
(a recorder closes its bag over what reached the disk, or leaves its .active for `bag reindex`); a failed
convert leaves nothing behind; the source is never touched.
Outside root the tests skip; in CI they fail when ROSTOOL_EXPECT_ROOT=1 says root was expected.
"""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from tests.support import (
    IN_CI,
    TESTDATA,
    debian,
    require_ros1_peers,
    rostool,
    rostool_popen,
    start_rospy_script,
    stop,
)
from tests.test_bag_play import wait_published
from tests.test_bag_record import BIG_PUBLISHER

SIZE = "2m"
FULL = re.compile(r"disk is full|No space left on device")


def _unavailable(why: str) -> None:
    if IN_CI and os.environ.get("ROSTOOL_EXPECT_ROOT") == "1":
        pytest.fail(why)
    pytest.skip(why)


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A fresh 2 MB tmpfs; unmounted at the end."""
    if os.geteuid() != 0:
        _unavailable("mounting a small tmpfs needs root")
    where = tmp_path / "small"
    where.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={SIZE}", "tmpfs", str(where)],
                             capture_output=True, text=True)  # fmt: skip
    if mounted.returncode != 0:
        _unavailable(f"cannot mount a tmpfs here: {mounted.stderr.strip()}")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


def _one_full_line(stderr: str) -> None:
    assert "Traceback" not in stderr and "internal error" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rostool: ") and FULL.search(lines[0]), stderr


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _values(path: Path) -> list[int]:
    """The counters of the recorded 'N:xxx' strings, read with rosbags' own reader."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if path.suffix == ".bag" else Stores.ROS2_JAZZY)
    with AnyReader([path], default_typestore=store) as reader:
        return [
            int(str(reader.deserialize(raw, c.msgtype).data).split(":")[0])
            for c, _t, raw in reader.messages()
        ]


def _consecutive(values: list[int], at_least: int) -> None:
    assert len(values) >= at_least and values == list(range(values[0], values[0] + len(values)))


@pytest.mark.parametrize(
    "fmt",
    ["bag", "mcap", "db3"],
)
def test_record_into_a_full_disk(
    debian_master: dict[str, str], tmp_path: Path, small_disk: Path, fmt: str
) -> None:
    require_ros1_peers()
    env = debian_master
    big = start_rospy_script(BIG_PUBLISHER, env, tmp_path, "big", ["/big", "50", "20000"])
    try:
        wait_published(env, "/big")
        recorder = rostool_popen(["bag", "record", "/big", "-O", str(small_disk / f"full.{fmt}")], env)
        _out, err = recorder.communicate(timeout=60)  # ends by itself when the disk is full
    finally:
        stop(big)
    assert recorder.returncode == 1, err
    _one_full_line(err)
    final, active = small_disk / f"full.{fmt}", small_disk / f"full.{fmt}.active"
    if fmt == "bag":  # the writer indexed what reached the disk; Debian's rosbag reads it
        info = debian(["rosbag", "info", "--yaml", str(final)], env)
        assert info.returncode == 0, info.stderr
        values = _values(final)
        _consecutive(values, 20)
        assert yaml.safe_load(info.stdout)["messages"] == len(values)
        return
    # .mcap/.db3: the bag, or its .active directory, which `bag reindex` makes readable once there is
    # space again. (An .mcap chunk is built in memory and written when closed: the one in flight is lost.)
    if final.exists():
        _consecutive(_values(final), 1)
        return
    assert active.is_dir(), "neither the bag nor its .active is left"
    moved = tmp_path / active.name
    subprocess.run(["cp", "-a", str(active), str(moved)], check=True)
    done = rostool(["bag", "reindex", str(moved)], env, timeout=60)
    assert done.returncode == 0, done.stderr
    _consecutive(_values(moved), 1)


def test_convert_into_a_full_disk(tmp_path: Path, small_disk: Path) -> None:
    source = tmp_path / "source.bag"
    _write_big_bag(source)
    before = _digest(source)
    env = dict(os.environ)
    for name in ("out.bag", "out.mcap", "out.db3", "out_dir"):
        result = rostool(["bag", "convert", str(source), str(small_disk / name)], env, timeout=120)
        assert result.returncode == 1, (name, result.stderr)
        _one_full_line(result.stderr)
        assert list(small_disk.iterdir()) == [], f"{name}: a failed convert left files behind"
    assert _digest(source) == before


def _write_big_bag(path: Path) -> None:
    """3 MB of std_msgs/String 'N:xxx...' messages (more than the small disk holds)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    string = store.types["std_msgs/msg/String"]
    with Writer(path) as writer:
        conn = writer.add_connection("/big", "std_msgs/msg/String", typestore=store)
        for i in range(150):
            data = f"{i}:" + "x" * 20_000
            writer.write(
                conn,
                1_700_000_000_000_000_000 + i * 10_000_000,
                store.serialize_ros1(string(data=data), "std_msgs/msg/String"),
            )


def test_reindex_on_a_full_disk(tmp_path: Path, small_disk: Path) -> None:
    """`bag reindex` needs room for the rebuilt copy: without it, one line, the cut-short original kept
    as it was and no temporary file left."""
    from tests.test_bag_reindex import _kill
    from tests.test_bag_support import write_ros1_bag

    bag = write_ros1_bag(small_disk / "killed.bag", count=3000)
    _kill(bag)
    mcap = small_disk / "cut.mcap"
    whole = (TESTDATA / "ros2" / "talker_mcap" / "talker.mcap").read_bytes()
    mcap.write_bytes(whole[: len(whole) * 6 // 10])
    fd = os.open(small_disk / "filler", os.O_WRONLY | os.O_CREAT)
    try:  # fill the disk up to its last bytes
        while True:
            os.write(fd, bytes(4096))
    except OSError:
        pass
    finally:
        os.close(fd)
    directory = small_disk / "run.mcap.active"  # what a killed ROS 2 recorder leaves
    directory.mkdir()
    os.link(mcap, directory / "run.mcap.active.mcap")
    for victim in (bag, mcap, directory):
        before = _digest(victim if victim.is_file() else directory / "run.mcap.active.mcap")
        result = rostool(["bag", "reindex", str(victim)], dict(os.environ), timeout=60)
        assert result.returncode == 1, result.stderr
        _one_full_line(result.stderr)
        assert _digest(victim if victim.is_file() else directory / "run.mcap.active.mcap") == before
        assert sorted(p.name for p in small_disk.iterdir()) == [
            "cut.mcap",
            "filler",
            "killed.bag",
            directory.name,
        ]
        assert [p.name for p in directory.iterdir()] == ["run.mcap.active.mcap"]
