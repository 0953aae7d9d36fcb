"""The ROS 2 graph daemon against real rclpy peers: listings through it equal direct listings, joins and
leaves show, a killed daemon or a stale socket is replaced, a daemon of another build is replaced, two
domains never mix, --no-daemon starts none, a socket directory that is not private is refused. Every
test has its own runtime directory (so xdist workers never share a daemon) and stops every daemon it
started."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import socket
import subprocess
import tempfile
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.ros2_backends import Tool
from tests.ros2_peers import RclpyPeer, StartPeer, held_locks
from tests.support import ros2_env, rostool, wait_until

ListFn = Callable[..., "subprocess.CompletedProcess[str]"]
# the lease of the peers these tests kill (Fast DDS's default, 20 s, made each such test wait 20 s)
LEASE = 4.0


def _daemon_dirs(env: dict[str, str]) -> dict[str, str]:
    # a short path: a Unix socket's path is limited to 107 bytes
    run = tempfile.mkdtemp(prefix="rtd")
    return {"XDG_RUNTIME_DIR": run, "XDG_STATE_HOME": os.path.join(run, "state"), **env}


@pytest.fixture
def graph_env() -> Iterator[dict[str, str]]:
    """The test's ROS 2 environment with the daemon allowed, in a runtime directory of its own; every
    daemon started in it is stopped at the end (and one that would not stop is killed, failing the test)."""
    env = _daemon_dirs({**ros2_env(), "ROSTOOL_NO_DAEMON": ""})
    run = Path(env["XDG_RUNTIME_DIR"])
    yield env
    rostool(["daemon", "stop", "--all"], env)
    left = [pid for pid in held_locks(run) if pid > 0]
    for pid in left:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    shutil.rmtree(run, ignore_errors=True)
    assert not left, f"daemons still running after `daemon stop --all`: {left}"


def status(env: dict[str, str]) -> dict[str, object]:
    done = rostool(["daemon", "status", "--json"], env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)  # type: ignore[no-any-return]


def started(env: dict[str, str]) -> dict[str, object]:
    done = rostool(["daemon", "start"], env, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == "The daemon has been started", done
    found = status(env)
    assert found["running"] is True
    return found


def names(done: subprocess.CompletedProcess[str]) -> list[str]:
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def answered_then_replaced(env: dict[str, str], node: str, old: dict[str, object]) -> dict[str, object]:
    """`node list` answers right (directly, without a word on stderr), and a new daemon then serves: its
    status."""
    listed = rostool(["node", "list"], env)
    assert names(listed) == [node] and listed.stderr == ""
    assert wait_until(lambda: status(env).get("pid") not in (None, old.get("pid")), timeout=20)
    assert names(rostool(["node", "list"], env)) == [node]
    return status(env)


LISTINGS = [
    ["topic", "list", "-t"],
    ["node", "list"],
    ["service", "list", "-t"],
    ["action", "list", "-t"],
    ["topic", "info", "/chatter", "-v"],
    ["topic", "type", "/chatter"],
    ["node", "info", "/talker"],
    ["service", "type", "/toggle"],
    ["service", "find", "std_srvs/srv/SetBool"],
    ["action", "info", "/fib"],
    ["node", "list", "--json"],
]
NODE_LISTS = [["node", "list"], ["node", "list", "--json"]]


def test_listings_through_the_daemon_equal_direct_ones(
    tool: Tool, start_peer: StartPeer, graph_env: dict[str, str], backend: str
) -> None:
    start_peer.together(["--name", "talker", "--talk", "/chatter", "--service", "/toggle"],
                        ["--name", "fibber", "--action", "/fib", "--listen", "/chatter"])  # fmt: skip
    started_ = tool(["daemon", "start"], timeout=60)
    assert started_.stdout.strip() == "The daemon has been started", started_.stderr
    running = json.loads(tool(["daemon", "status", "--json"]).stdout)
    assert running["running"] is True and running["backend"] == backend
    assert running["domain"] == int(graph_env["ROS_DOMAIN_ID"])

    seen: list[str] = []

    def no_direct_tool_left() -> bool:  # the direct calls' own nodes leave as their processes end
        seen[:] = tool(["node", "list"]).stdout.split()
        return not any(n.startswith("/rostool_") for n in seen)

    def both(args: list[str]) -> tuple[subprocess.CompletedProcess[str], subprocess.CompletedProcess[str]]:
        """The served answer, and the direct one (a direct rclpy listing may answer before discovery is
        complete, the daemon's is: a few tries)."""
        served = tool(args)
        direct = [tool([*args, "--no-daemon"])]
        while direct[-1].stdout != served.stdout and len(direct) < 8:
            direct.append(tool([*args, "--no-daemon"]))
        return served, direct[-1]

    def check(
        args: list[str], served: subprocess.CompletedProcess[str], direct: subprocess.CompletedProcess[str]
    ) -> None:
        assert served.returncode == 0 and served.stderr_lines == [], (args, served.stderr)  # type: ignore[attr-defined]
        assert direct.returncode == 0, (args, direct.stderr)
        assert served.stdout == direct.stdout, args

    # a direct rostool on rclpy is a node (/rostool_PID) for a moment: the node lists one after the other,
    # each once no direct run's node is left; the other listings never show a rostool, so side by side
    for args in NODE_LISTS:
        assert wait_until(no_direct_tool_left, timeout=15), (args, seen)
        check(args, *both(args))
    others = [args for args in LISTINGS if args not in NODE_LISTS]
    with ThreadPoolExecutor(max_workers=len(others)) as pool:
        answers = list(pool.map(both, others))
    for args, (served, direct) in zip(others, answers, strict=True):
        check(args, served, direct)
    assert "/talker" in tool(["node", "list"]).stdout.split()
    assert json.loads(tool(["daemon", "status", "--json"]).stdout)["running"] is True


def test_joins_and_clean_leaves_show_at_once(
    tool: Tool, start_peer: StartPeer, graph_env: dict[str, str]
) -> None:
    start_peer("--name", "first")
    assert tool(["daemon", "start"], timeout=60).returncode == 0
    assert tool(["node", "list"]).stdout.split() == ["/first"]
    late = start_peer("--name", "late", "--talk", "/late_topic")
    assert wait_until(lambda: "/late" in tool(["node", "list"]).stdout.split(), timeout=20)
    assert "/late_topic" in tool(["topic", "list"]).stdout.split()
    late.stop()
    assert wait_until(lambda: tool(["node", "list"]).stdout.split() == ["/first"], timeout=20)
    assert "/late_topic" not in tool(["topic", "list"]).stdout.split()


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_peer_killed_with_sigkill_leaves_at_its_lease_expiry(
    start_peer: StartPeer, graph_env: dict[str, str]
) -> None:
    start_peer("--name", "steady")
    doomed = start_peer("--name", "doomed", "--talk", "/doomed_topic", lease=LEASE)
    started(graph_env)
    assert names(rostool(["node", "list"], graph_env)) == ["/doomed", "/steady"]
    doomed.proc.kill()
    doomed.proc.wait()
    # the daemon drops the node and its topic when the lease the peer announced expires
    assert wait_until(lambda: names(rostool(["node", "list"], graph_env)) == ["/steady"], timeout=45)
    assert "/doomed_topic" not in names(rostool(["topic", "list"], graph_env))


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_killed_daemon_is_replaced_and_the_query_still_answers(
    start_peer: StartPeer, graph_env: dict[str, str]
) -> None:
    start_peer("--name", "survivor")
    first = started(graph_env)
    os.kill(int(str(first["pid"])), signal.SIGKILL)
    assert wait_until(lambda: not status(graph_env)["running"])
    assert Path(str(first["socket"])).exists()  # the dead daemon's stale socket
    second = answered_then_replaced(graph_env, "/survivor", first)
    assert second["pid"] != first["pid"]


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_stale_socket_file_is_replaced(start_peer: StartPeer, graph_env: dict[str, str]) -> None:
    start_peer("--name", "stale_check")
    path = Path(str(status(graph_env)["socket"]))
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    orphan = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    orphan.bind(str(path))  # bound, never listening, closed: what a killed process leaves
    orphan.close()
    os.chmod(path, 0o600)
    answered_then_replaced(graph_env, "/stale_check", {})


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_daemon_of_another_build_is_replaced(start_peer: StartPeer, graph_env: dict[str, str]) -> None:
    start_peer("--name", "versioned")
    old = started({**graph_env, "ROSTOOL_DAEMON_BUILD": "0.0.1-old"})
    assert old["build"] == "0.0.1-old"
    new = answered_then_replaced(graph_env, "/versioned", old)
    assert new["build"] != "0.0.1-old"


@pytest.mark.parametrize("distro", ["jazzy"])
def test_two_domains_side_by_side_never_mix(
    start_peer: StartPeer, graph_env: dict[str, str], tmp_path: Path
) -> None:
    start_peer("--name", "in_first")
    other = {
        **{**ros2_env(), "ROSTOOL_NO_DAEMON": ""},
        **{k: graph_env[k] for k in ("XDG_RUNTIME_DIR", "XDG_STATE_HOME")},
    }
    second_peer = RclpyPeer("jazzy", other, tmp_path, ["--name", "in_second"])
    try:
        second_peer.wait_for("ready", timeout=30)
        first, second = started(graph_env), started(other)
        assert first["pid"] != second["pid"] and first["socket"] != second["socket"]
        assert (first["domain"], second["domain"]) == (
            int(graph_env["ROS_DOMAIN_ID"]),
            int(other["ROS_DOMAIN_ID"]),
        )
        for _ in range(3):
            assert names(rostool(["node", "list"], graph_env)) == ["/in_first"]
            assert names(rostool(["node", "list"], other)) == ["/in_second"]
    finally:
        second_peer.stop()


@pytest.mark.parametrize("distro", ["jazzy"])
def test_no_daemon_starts_none(start_peer: StartPeer, graph_env: dict[str, str]) -> None:
    start_peer("--name", "alone")
    assert names(rostool(["node", "list", "--no-daemon"], graph_env)) == ["/alone"]
    assert names(rostool(["topic", "list", "--no-daemon"], graph_env)) == ["/parameter_events", "/rosout"]
    assert names(rostool(["node", "list"], {**graph_env, "ROSTOOL_NO_DAEMON": "1"})) == ["/alone"]
    assert not list(Path(graph_env["XDG_RUNTIME_DIR"]).glob("rostool/*.sock"))
    assert status(graph_env)["running"] is False


def test_an_empty_graph_lists_nothing_and_succeeds(graph_env: dict[str, str]) -> None:
    started(graph_env)
    for args in (["topic", "list"], ["node", "list"], ["service", "list"], ["action", "list"]):
        done = rostool(args, graph_env)
        assert (done.returncode, done.stdout, done.stderr) == (0, "", ""), args
    assert status(graph_env)["graph"] == {"nodes": 0, "topics": 0, "services": 0, "actions": 0}


@pytest.mark.parametrize("distro", ["jazzy"])
@pytest.mark.parametrize("wrong", ["mode", "owner"])
def test_a_socket_directory_that_is_not_private_is_refused(
    start_peer: StartPeer, graph_env: dict[str, str], wrong: str
) -> None:
    start_peer("--name", "refused")
    folder = Path(graph_env["XDG_RUNTIME_DIR"]) / "rostool"
    folder.mkdir(mode=0o700)
    if wrong == "mode":
        folder.chmod(0o755)
        expected = "chmod 700"
    else:
        if os.getuid() != 0:
            pytest.skip("giving a directory to another user needs root")
        os.chown(folder, 65534, 65534)
        expected = "belongs to uid 65534"
    start = rostool(["daemon", "start"], graph_env)
    assert start.returncode == 1 and len(start.stderr.splitlines()) == 1 and expected in start.stderr
    listed = rostool(["node", "list"], graph_env)
    assert names(listed) == ["/refused"]  # still answered, directly
    assert len(listed.stderr.splitlines()) == 1 and expected in listed.stderr
    assert not list(folder.iterdir())


@pytest.mark.parametrize("distro", ["jazzy"])
def test_spin_time_is_the_direct_listings_discovery_wait(
    tool: Tool, tool_popen: Callable[[list[str]], subprocess.Popen[str]],
    start_peer: StartPeer, graph_env: dict[str, str],
) -> None:  # fmt: skip
    # an empty graph: the listing waits the given time, not its own window, and says so
    empty = tool(["node", "list", "--no-daemon", "--spin-time", "0.5"])
    assert empty.returncode == 1 and "within 0.5 s" in empty.stderr, empty.stderr
    # a node that starts after the listing did is listed: it spins its whole time (as ros2cli's DirectNode;
    # 10 s: the late peer is ready in 1-4 s, and a new participant announces itself at once)
    listing = tool_popen(["topic", "list", "--no-daemon", "--spin-time", "10"])
    start_peer("--name", "late_spinner", "--talk", "/late_spin")
    assert listing.poll() is None, "the listing answered before its spin time"
    out, err = listing.communicate(timeout=60)
    assert listing.returncode == 0 and "/late_spin" in out.split(), err
    # a running daemon answers: --spin-time only applies without one (ros2cli's words)
    assert tool(["daemon", "start"], timeout=60).returncode == 0
    served = tool(["topic", "list", "--spin-time", "90"], timeout=60)  # a direct answer would take 90 s
    assert served.returncode == 0 and "/late_spin" in served.stdout.split(), served.stderr


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_peer_killed_with_sigkill_is_never_listed_after_its_lease(
    tool: Tool, start_peer: StartPeer, graph_env: dict[str, str]
) -> None:
    start_peer("--name", "keeper")
    doomed = start_peer(
        "--name", "killed", "--talk", "/killed_topic", "--service", "/killed_srv", lease=LEASE
    )
    assert tool(["daemon", "start"], timeout=60).returncode == 0
    assert wait_until(lambda: tool(["node", "list"]).stdout.split() == ["/keeper", "/killed"], timeout=20)
    doomed.proc.kill()
    doomed.proc.wait()
    # gone once its lease expires, and then never listed again
    assert wait_until(lambda: tool(["node", "list"]).stdout.split() == ["/keeper"], timeout=45)
    for args, gone in ((["topic", "list"], "/killed_topic"), (["service", "list"], "/killed_srv")):
        listed = tool(args)
        assert listed.returncode == 0 and gone not in listed.stdout.split(), (args, listed.stdout)
    assert tool(["node", "list"]).stdout.split() == ["/keeper"]


def test_a_daemon_a_verb_started_ends_sooner_when_idle_and_status_says_so(graph_env: dict[str, str]) -> None:
    """Issue 37: daemons a verb starts (one per domain, backend and environment) end after 900 s without a
    query or relay, so they do not pile up; one started by `daemon start` keeps ros2's 7200 s."""
    env = graph_env
    rostool(["node", "list"], env)  # a cold call (of an empty graph: exit 1) starts the daemon for itself
    assert wait_until(lambda: status(env)["running"] is True, timeout=30)
    found = status(env)
    assert (found["auto_started"], found["idle_exit"]) == (True, 900)
    text = rostool(["daemon", "status"], env).stdout
    assert "  exits after: 900 s without a query or relay (started by a verb; idle for " in text, text
    assert rostool(["daemon", "stop"], env).returncode == 0
    found = started(env)
    assert (found["auto_started"], found["idle_exit"]) == (False, 7200)
    assert rostool(["daemon", "stop"], env).returncode == 0

    short = {**env, "ROSTOOL_DAEMON_IDLE": "3"}  # the user's own choice, for both kinds
    rostool(["node", "list"], short)
    logs = Path(env["XDG_STATE_HOME"]) / "rostool"

    def ended_idle() -> bool:
        return any("idle for 3 s: exiting" in log.read_text() for log in logs.glob("*.log"))

    assert wait_until(ended_idle, timeout=40)  # gone by itself
    assert status(short)["running"] is False
