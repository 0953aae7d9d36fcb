"""Issue 25: rosbag2's control services. `bag play` on a ROS 2 graph serves /rosbag2_player's pause,
resume, toggle_paused, is_paused, get_rate, set_rate, play_next, burst, seek and stop (rosbag2_interfaces'
types, built into rostool); each is called here with `rostool --ros2 service call` and its effect observed
by a real rclpy subscriber. The rclpy backend serves them where rosbag2_interfaces imports, else it plays
without them after one warning; its service server is checked with the real `ros2 service call`."""

from __future__ import annotations

import itertools
import re
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from rostool.bag.player_services import PLAYER_SERVICES
from tests.ros2_peers import PEERS_DIR, RclpyPeer, peer_env, peer_python, rostool_rclpy_popen
from tests.support import Watched, rostool, rostool_popen

Start = Callable[..., RclpyPeer]
PERIOD_NS = 100_000_000
START_NS = 1_700_000_000 * 1_000_000_000
PAUSED = "[INFO] [rosbag2_player]"  # nothing else is printed while paused without a terminal


def write_strings_bag(path: Path, count: int) -> None:
    """An .mcap bag of std_msgs/String 'n N' on /chatter, one every 0.1 s."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    string = store.types["std_msgs/msg/String"]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        for n in range(count):
            data = store.serialize_cdr(string(data=f"n {n}"), "std_msgs/msg/String")
            writer.write(conn, START_NS + n * PERIOD_NS, data)


def call(env: dict[str, str], service: str, kind: str, request: str = "{}") -> str:
    """`rostool --ros2 service call`: the response line (`...Response(field=value)`)."""
    done = rostool(["--ros2", "service", "call", f"/rosbag2_player/{service}",
                    f"rosbag2_interfaces/srv/{kind}", request], env, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "response:" in done.stdout, done.stdout
    return done.stdout.split("response:", 1)[1].strip()


def heard(peer: RclpyPeer) -> list[int]:
    return [int(e["data"].split()[1]) for e in peer.of("heard")]


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_player_services_pause_step_burst_rate_seek_and_resume(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    bag = tmp_path / "strings"
    write_strings_bag(bag, 60)
    listener = start_peer("--name", "listener", "--listen", "/chatter")
    play = Watched(rostool_popen(["--ros2", "bag", "play", str(bag), "-p", "--wait-for-subscribers"],
                                 graph_env, stdin=subprocess.DEVNULL))  # fmt: skip
    try:
        assert call(graph_env, "is_paused", "IsPaused").endswith("(paused=True)")
        assert call(graph_env, "play_next", "PlayNext").endswith("(success=True)")
        assert listener.wait_for("heard", lambda e: e["data"] == "n 0", timeout=20)
        assert call(graph_env, "burst", "Burst", "{num_messages: 3}").endswith("(actually_burst=3)")
        assert listener.wait_for("heard", lambda e: e["data"] == "n 3", timeout=20)
        assert call(graph_env, "set_rate", "SetRate", "{rate: 2.5}").endswith("(success=True)")
        assert call(graph_env, "set_rate", "SetRate", "{rate: -1.0}").endswith("(success=False)")
        assert call(graph_env, "get_rate", "GetRate").endswith("(rate=2.5)")
        past_end = f"{{time: {{sec: {START_NS // 10**9 + 60}, nanosec: 0}}}}"
        assert call(graph_env, "seek", "Seek", past_end).endswith("(success=False)")
        to_20 = f"{{time: {{sec: {START_NS // 10**9 + 2}, nanosec: 0}}}}"
        assert call(graph_env, "seek", "Seek", to_20).endswith("(success=True)")
        assert call(graph_env, "play_next", "PlayNext").endswith("(success=True)")
        assert listener.wait_for("heard", lambda e: e["data"] == "n 20", timeout=20)
        assert heard(listener) == [0, 1, 2, 3, 20]  # still paused: nothing more was published
        call(graph_env, "toggle_paused", "TogglePaused")
        assert listener.wait_for("heard", lambda e: e["data"] == "n 59", timeout=30)
        assert play.proc.wait(timeout=30) == 0
    finally:
        _out, err = play.stop()
    assert heard(listener) == [0, 1, 2, 3, *range(20, 60)], err
    assert "services are not served" not in err and "Traceback" not in err, err


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_player_services_pause_resume_and_stop(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    bag = tmp_path / "strings"
    write_strings_bag(bag, 600)  # a minute: stopped long before its end
    listener = start_peer("--name", "listener", "--listen", "/chatter")
    play = Watched(rostool_popen(["--ros2", "bag", "play", str(bag), "--wait-for-subscribers"], graph_env,
                                 stdin=subprocess.DEVNULL))  # fmt: skip
    try:
        assert listener.wait_for("heard", lambda e: e["data"] == "n 2", timeout=30)
        ros2 = PEERS_DIR / "jazzy" / "bin" / "ros2"  # the real ros2 lists them with their types
        wanted = [f"/rosbag2_player/{name} [rosbag2_interfaces/srv/{kind}]"
                  for name, (kind, _value) in PLAYER_SERVICES.items()]  # fmt: skip
        listed = ""
        for _attempt in range(5):  # a new participant's discovery may take longer than one spin
            listed = subprocess.run([str(ros2), "service", "list", "-t", "--no-daemon", "--spin-time", "2"],
                                    env=peer_env(graph_env, tmp_path), capture_output=True, text=True,
                                    timeout=60).stdout  # fmt: skip
            if all(line in listed for line in wanted):
                break
        assert all(line in listed for line in wanted), listed
        call(graph_env, "pause", "Pause")
        assert call(graph_env, "is_paused", "IsPaused").endswith("(paused=True)")
        before = heard(listener)
        assert call(graph_env, "play_next", "PlayNext").endswith("(success=True)")
        assert listener.wait_for("heard", lambda e: len(heard(listener)) > len(before), timeout=20)
        assert heard(listener) == list(range(len(before) + 1))  # exactly the next one
        call(graph_env, "resume", "Resume")
        assert call(graph_env, "is_paused", "IsPaused").endswith("(paused=False)")
        assert call(graph_env, "burst", "Burst", "{num_messages: 2}").endswith("(actually_burst=0)")
        call(graph_env, "stop", "Stop")
        assert play.proc.wait(timeout=30) == 0
    finally:
        _out, err = play.stop()
    played = heard(listener)
    assert played == list(range(len(played))) and len(played) < 600, played
    assert "burst is done only while paused" in err and "Traceback" not in err, err


def test_rclpy_backend_plays_without_the_services_it_cannot_type(
    distro: str, graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """rosbag2_interfaces is not in the peer venvs: one warning, then the bag plays as before."""
    bag = tmp_path / "strings"
    write_strings_bag(bag, 5)
    listener = start_peer("--name", "listener", "--listen", "/chatter")
    play = rostool_rclpy_popen(["--ros2", "bag", "play", str(bag), "--wait-for-subscribers"], graph_env,
                               tmp_path, distro)  # fmt: skip
    _out, err = play.communicate(timeout=90)
    assert play.returncode == 0, err
    assert listener.wait_for("heard", lambda e: e["data"] == "n 4", timeout=20)
    assert heard(listener) == [0, 1, 2, 3, 4]
    warnings = [line for line in err.splitlines() if "services are not served" in line]
    assert len(warnings) == 1, err
    assert "/rosbag2_player" in warnings[0] and "rosbag2_interfaces" in warnings[0]


SERVE_SETBOOL = """
import sys, time
from rostool.graph.rclpy.graph import RclpyGraph
graph = RclpyGraph("served")
served = graph.serve_service("/flip", "std_srvs/srv/SetBool",
                             lambda request: {"success": not request.data, "message": f"got {request.data}"})
print("serving", flush=True)
sys.stdin.read()
served.close()
graph.close()
"""


def test_rclpy_backend_serves_a_service_the_real_ros2_calls(
    distro: str, graph_env: dict[str, str], tmp_path: Path
) -> None:
    """`serve_service` on the rclpy backend (std_srvs imports there), answered to the real ros2 CLI."""
    env = peer_env(graph_env, tmp_path)
    server = Watched(subprocess.Popen([str(peer_python(distro)), "-c", SERVE_SETBOOL], env=env,
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      text=True))  # fmt: skip
    try:
        assert server.wait_for(lambda out: "serving" in out, 60), server.stop()
        ros2 = PEERS_DIR / "jazzy" / "bin" / "ros2"  # the real ros2 (the kilted venv has rclpy only)
        done = subprocess.run([str(ros2), "service", "call", "/flip", "std_srvs/srv/SetBool", "{data: true}"],
                              env=env, capture_output=True, text=True, timeout=60)  # fmt: skip
    finally:
        assert server.proc.stdin is not None
        server.proc.stdin.close()
        server.proc.wait(timeout=30)
    assert done.returncode == 0, done.stderr
    assert re.search(r"SetBool_Response\(success=False, message='got True'\)", done.stdout), done.stdout


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_recorder_snapshot_service_writes_the_held_second(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """`bag record --snapshot-mode` serves NODE/snapshot (rosbag2's /rosbag2_recorder/snapshot; --node-name
    renames it): the call answers once the messages held (the last second) are written; what comes after
    it is never written."""
    from rosbags.highlevel import AnyReader

    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    bag = tmp_path / "snap"
    args = ["--ros2", "bag", "record", "/chatter", "-o", str(bag), "--snapshot-mode",
            "--max-cache-duration", "1", "--node-name", "snapper"]  # fmt: skip
    recorder = Watched(rostool_popen(args, graph_env, stdin=subprocess.DEVNULL))
    try:
        matched = int(talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)["count"])
        talker.wait_for("published", lambda e: e["count"] > matched + 40, timeout=30)
        done = rostool(["--ros2", "service", "call", "/snapper/snapshot",
                        "rosbag2_interfaces/srv/Snapshot"], graph_env, timeout=60)  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert done.stdout.rstrip().endswith("Snapshot_Response(success=True)"), done.stdout
        answered = talker.of("published")[-1]["count"]  # reported once a second: up to 20 behind
        later = int(talker.wait_for("published", lambda e: e["count"] > answered + 40, timeout=30)["count"])
    finally:
        _out, err = recorder.stop()
    assert "Taking a snapshot." in err and "Traceback" not in err, err
    with AnyReader([bag]) as reader:
        rows = [
            (stamp, int(reader.deserialize(data, conn.msgtype).data.removeprefix("hello ")))
            for conn, stamp, data in reader.messages()
        ]
    numbers = [n for _t, n in rows]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers))), numbers  # one run, no gap
    assert rows[-1][0] - rows[0][0] <= 1_000_000_000, rows  # the last second only
    # held before the call: nothing of the second (and more) published after it
    assert numbers[0] > matched and numbers[-1] < later - 15, (matched, later, numbers)


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_recorder_pause_resume_is_paused_and_split_services(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """/rosbag2_recorder/pause, resume and is_paused: what arrives while paused is not recorded;
    split_bagfile starts the next file and loses nothing."""
    import yaml
    from rosbags.highlevel import AnyReader

    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    bag = tmp_path / "paused"
    recorder = Watched(rostool_popen(["--ros2", "bag", "record", "/chatter", "-o", str(bag)], graph_env,
                                     stdin=subprocess.DEVNULL))  # fmt: skip

    def recorder_call(service: str, kind: str) -> str:
        done = rostool(["--ros2", "service", "call", f"/rosbag2_recorder/{service}",
                        f"rosbag2_interfaces/srv/{kind}"], graph_env, timeout=60)  # fmt: skip
        assert done.returncode == 0, done.stderr
        return done.stdout.rstrip()

    try:
        matched = int(talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)["count"])
        talker.wait_for("published", lambda e: e["count"] > matched + 20, timeout=30)
        assert recorder_call("is_paused", "IsPaused").endswith("IsPaused_Response(paused=False)")
        recorder_call("pause", "Pause")
        assert recorder_call("is_paused", "IsPaused").endswith("IsPaused_Response(paused=True)")
        at_pause = talker.of("published")[-1]["count"]
        talker.wait_for("published", lambda e: e["count"] > at_pause + 60, timeout=30)
        recorder_call("resume", "Resume")
        assert recorder_call("is_paused", "IsPaused").endswith("IsPaused_Response(paused=False)")
        at_resume = talker.of("published")[-1]["count"]
        talker.wait_for("published", lambda e: e["count"] > at_resume + 40, timeout=30)
        recorder_call("split_bagfile", "SplitBagfile")
        at_split = talker.of("published")[-1]["count"]
        talker.wait_for("published", lambda e: e["count"] > at_split + 40, timeout=30)
    finally:
        _out, err = recorder.stop()
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["relative_file_paths"] == ["paused_0.mcap", "paused_1.mcap"], info
    assert all(f["message_count"] > 10 for f in info["files"]), info["files"]
    assert "Pausing recording." in err and "Resuming recording." in err and "Traceback" not in err, err
    with AnyReader([bag]) as reader:
        numbers = [int(reader.deserialize(data, c.msgtype).data.removeprefix("hello "))
                   for c, _t, data in reader.messages()]  # fmt: skip
    gaps = [(a, b) for a, b in itertools.pairwise(numbers) if b != a + 1]
    assert len(gaps) == 1 and gaps[0][1] - gaps[0][0] > 20, gaps  # one hole: the paused time


# --- ros2 bag record --storage-config-file ---------------------------------------------------------------


def record_some(env: dict[str, str], talker: RclpyPeer, args: list[str], topic: str = "/chatter") -> str:
    """Record `topic` (the talker's, which nothing else recorded) with `args` until 40 more messages were
    published; the recorder's stderr."""
    recorder = Watched(rostool_popen(["--ros2", "bag", "record", topic, *args], env,
                                     stdin=subprocess.DEVNULL))  # fmt: skip
    try:
        matched = int(talker.wait_for("matched", lambda e: e["subscribers"] >= 1, timeout=30)["count"])
        talker.wait_for("published", lambda e: e["count"] > matched + 40, timeout=30)
    finally:
        _out, err = recorder.stop()
    assert recorder.proc.returncode == 0, err
    return err


def contiguous_numbers(bag: Path) -> list[int]:
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:
        numbers = [int(reader.deserialize(data, c.msgtype).data.removeprefix("hello "))
                   for c, _t, data in reader.messages()]  # fmt: skip
    assert len(numbers) >= 20 and numbers == list(range(numbers[0], numbers[0] + len(numbers))), numbers
    return numbers


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_storage_config_file_sets_mcap_compression_and_chunk_size(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    from mcap.reader import make_reader

    config = tmp_path / "mcap_writer_options.yaml"
    config.write_text("compression: Zstd\ncompressionLevel: Fast\nchunkSize: 1024\nnoChunkCRC: false\n")
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "50")
    bag = tmp_path / "configured"
    record_some(graph_env, talker, ["-o", str(bag), "--storage-config-file", str(config)])
    contiguous_numbers(bag)
    with open(bag / "configured_0.mcap", "rb") as stream:  # the mcap library reads the file on its own
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        chunks = summary.chunk_indexes
        assert len(chunks) >= 2 and {c.compression for c in chunks} == {"zstd"}, chunks
        assert all(1024 <= c.uncompressed_size < 1024 + 512 for c in chunks[:-1]), chunks
        assert reader.get_header().library == "rostool"
        assert summary.statistics is not None and summary.statistics.message_count >= 20


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_storage_preset_profiles_and_a_config_file_over_them(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    """zstd_small (zstd, 4 MiB chunks) with the file's chunkSize over it; fastwrite writes no chunks."""
    from mcap.reader import make_reader

    config = tmp_path / "smaller_chunks.yaml"
    config.write_text("chunkSize: 2048\n")
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "50")
    other = start_peer("--name", "other", "--talk", "/other", "--rate", "50")
    small, fast = tmp_path / "small", tmp_path / "fast"
    record_some(graph_env, talker, ["-o", str(small), "--storage-preset-profile", "zstd_small",
                                    "--storage-config-file", str(config)])  # fmt: skip
    record_some(graph_env, other, ["-o", str(fast), "--storage-preset-profile", "fastwrite"], "/other")
    contiguous_numbers(small)
    with open(small / "small_0.mcap", "rb") as stream:
        summary = make_reader(stream).get_summary()
        assert summary is not None
        chunks = summary.chunk_indexes
        assert len(chunks) >= 2 and {c.compression for c in chunks} == {"zstd"}, chunks
        assert all(2048 <= c.uncompressed_size < 2048 + 512 for c in chunks[:-1]), chunks
    later = contiguous_numbers(fast)
    with open(fast / "fast_0.mcap", "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes == []  # messages straight in the data section
        stream.seek(0)
        assert len(list(make_reader(stream).iter_messages())) == len(later)


@pytest.mark.parametrize("distro", ["jazzy"], indirect=True)
def test_storage_config_file_runs_sqlite3_pragmas(
    graph_env: dict[str, str], start_peer: Start, tmp_path: Path
) -> None:
    import sqlite3

    config = tmp_path / "sqlite3.yaml"
    pragmas = "['page_size = 8192', 'application_id = 4242', 'journal_mode = MEMORY']"
    config.write_text(f"write:\n  pragmas: {pragmas}\n")
    talker = start_peer("--name", "talker", "--talk", "/chatter", "--rate", "50")
    bag = tmp_path / "pragmas"
    record_some(graph_env, talker, ["-o", str(bag), "-s", "sqlite3", "--storage-config-file", str(config)])
    contiguous_numbers(bag)
    with sqlite3.connect(bag / "pragmas_0.db3") as db:
        assert db.execute("PRAGMA page_size").fetchone()[0] == 8192  # set before the tables were made
        assert db.execute("PRAGMA application_id").fetchone()[0] == 4242


@pytest.mark.parametrize(
    ("text", "storage", "said"),
    [
        ("chunksize: 1024\n", "mcap", "unknown mcap option chunksize"),
        ("compression: Brotli\n", "mcap", "compression must be one of None, Lz4, Zstd, not 'Brotli'"),
        ("chunkSize: -5\n", "mcap", "chunkSize must be a positive number of bytes"),
        ("noChunking: maybe\n", "mcap", "noChunking must be true or false"),
        ("write:\n  pragmas: ['x; DROP TABLE messages']\n", "sqlite3", "bad pragma 'x; DROP TABLE messages'"),
        ("writes: {}\n", "sqlite3", "unknown sqlite3 option writes"),
        (None, "mcap", "--storage-preset-profile resilient: unknown for mcap storage (known: fastwrite, "),
    ],
)
def test_storage_config_file_refuses_bad_options_in_one_line(
    text: str | None, storage: str, said: str, tmp_path: Path
) -> None:
    from tests.support import ros2_env

    config = tmp_path / "config.yaml"
    given = ["--storage-preset-profile", "resilient"]
    if text is not None:
        config.write_text(text)
        given = ["--storage-config-file", str(config)]
    bag = tmp_path / "never"
    done = rostool(["--ros2", "bag", "record", "/chatter", "-o", str(bag), "-s", storage, *given], ros2_env(),
                   timeout=60)  # fmt: skip
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and said in lines[0] and given[1] in lines[0], done.stderr
    assert not bag.exists()
