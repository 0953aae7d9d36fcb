"""The first call when no graph daemon runs yet (issue 21's cold call), against real rclpy peers: it answers
completely and directly, and starts the daemon only once its answer is known (a daemon started before
would be one more participant its listing waits for), except on the rclpy backend, whose direct listing
waits a floor of seconds anyway: there the daemon starts beside it and serves sooner. The DDS graph's
ros_discovery_info reader is made once the participants seen have described their endpoints (a Fast DDS
peer then heartbeats its nodes to it at once; made before, the reader waits for the peer's next 3 s
heartbeat)."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.ros2_peers import RclpyPeer, rostool_rclpy, rostool_rclpy_popen
from tests.support import rostool, rostool_popen, wait_until


@pytest.fixture
def cold_env(graph_env: dict[str, str]) -> Iterator[dict[str, str]]:
    """The test's environment with the daemon allowed, in a runtime directory of its own (none runs yet);
    every daemon started in it is stopped at the end."""
    run = tempfile.mkdtemp(prefix="rtc")  # short: a Unix socket's path is limited to 107 bytes
    env = {**graph_env, "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": run,
           "XDG_STATE_HOME": os.path.join(run, "state"), "ROSTOOL_ROS2_BACKEND": "dds"}  # fmt: skip
    yield env
    rostool(["daemon", "stop", "--all"], env)
    shutil.rmtree(run, ignore_errors=True)


def daemon_status(env: dict[str, str]) -> dict[str, Any]:
    done = rostool(["daemon", "status", "--json"], env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)  # type: ignore[no-any-return]


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_cold_call_answers_completely_then_a_daemon_serves(
    start_peer: Callable[..., RclpyPeer], cold_env: dict[str, str]
) -> None:
    for i in range(3):
        start_peer("--name", f"cold_{i}", "--talk", f"/cold_talk_{i}")
    expected = ["/cold_0", "/cold_1", "/cold_2"]
    assert daemon_status(cold_env)["running"] is False
    listed = rostool(["node", "list"], cold_env)
    assert (listed.returncode, listed.stderr) == (0, "")
    assert listed.stdout.split() == expected  # every node, not the daemon it started (hidden, started after)
    assert wait_until(lambda: daemon_status(cold_env)["running"] is True, timeout=30)
    assert rostool(["node", "list"], cold_env).stdout.split() == expected  # now through the daemon
    assert daemon_status(cold_env)["graph"]["nodes"] == 3


@pytest.mark.parametrize("distro", ["jazzy"])
def test_a_cold_rclpy_call_starts_its_daemon_while_it_waits_for_discovery(
    start_peer: Callable[..., RclpyPeer], cold_env: dict[str, str], tmp_path: Path, distro: str
) -> None:
    for i in range(2):
        start_peer("--name", f"beside_{i}", "--talk", f"/beside_{i}")
    logs = Path(cold_env["XDG_STATE_HOME"]) / "rostool"
    call = rostool_rclpy_popen(["node", "list"], cold_env, tmp_path, distro)
    started = time.monotonic()
    spawned: float | None = None  # when the daemon's log (opened as it is spawned) appeared
    while call.poll() is None and time.monotonic() - started < 30:
        if spawned is None and any(logs.glob("rclpy-d*.log")):
            spawned = time.monotonic()
        time.sleep(0.02)
    ended = time.monotonic()
    out, _err = call.communicate(timeout=30)
    assert call.returncode == 0
    assert out.split() == ["/beside_0", "/beside_1"]  # complete, and no daemon node (hidden) in it
    # spawned as the direct listing began, not once it was done (it then waits 2 s or more for discovery)
    assert spawned is not None and ended - spawned > 1.5, (spawned, ended)

    status = rclpy_status(cold_env, tmp_path, distro)
    assert wait_until(lambda: status()["running"] is True, timeout=30)
    served = rostool_rclpy(["node", "list"], cold_env, tmp_path, distro)
    assert served.stdout.split() == ["/beside_0", "/beside_1"]


def rclpy_status(env: dict[str, str], tmp_path: Path, distro: str) -> Callable[[], dict[str, Any]]:
    """`daemon status --json` of the rclpy backend's daemon, each call a new rostool."""

    def status() -> dict[str, Any]:
        done = rostool_rclpy(["daemon", "status", "--json"], env, tmp_path, distro)
        return json.loads(done.stdout)  # type: ignore[no-any-return]

    return status


@contextlib.contextmanager
def rclpy_daemon_starting(env: dict[str, str], tmp_path: Path, distro: str) -> Iterator[Callable[[], Any]]:
    """`daemon start` of the rclpy backend, entered once its daemon holds its lock but does not serve yet
    (it settles its graph first: seconds on this backend), left once it serves; yields `rclpy_status`."""
    status = rclpy_status(env, tmp_path, distro)
    starting = rostool_rclpy_popen(["daemon", "start"], env, tmp_path, distro)
    try:
        assert wait_until(lambda: status().get("starting") is True, timeout=30)
        yield status
        assert starting.wait(timeout=30) == 0
    finally:
        starting.kill()
        starting.communicate()


@pytest.mark.parametrize("distro", ["jazzy"])
def test_an_rclpy_call_made_while_its_daemon_starts_is_answered_by_that_daemon(
    start_peer: Callable[..., RclpyPeer], cold_env: dict[str, str], tmp_path: Path, distro: str
) -> None:
    for i in range(2):
        start_peer("--name", f"waiting_{i}", "--talk", f"/waiting_{i}")
    with rclpy_daemon_starting(cold_env, tmp_path, distro) as status:
        listed = rostool_rclpy(["node", "list"], cold_env, tmp_path, distro)
        assert (listed.returncode, listed.stdout.split()) == (0, ["/waiting_0", "/waiting_1"])
    assert status()["queries"] >= 1  # the listing was that daemon's answer, not a direct one


@pytest.mark.parametrize("distro", ["jazzy"])
def test_with_spin_time_a_call_answers_directly_though_its_daemon_starts(
    start_peer: Callable[..., RclpyPeer], cold_env: dict[str, str], tmp_path: Path, distro: str
) -> None:
    start_peer("--name", "spun", "--talk", "/spun")
    with rclpy_daemon_starting(cold_env, tmp_path, distro) as status:
        listed = rostool_rclpy(["node", "list", "--spin-time", "4"], cold_env, tmp_path, distro)
        assert (listed.returncode, listed.stdout.split()) == (0, ["/spun"])
    assert status()["queries"] == 0  # ros2cli's meaning: the direct listing waited the time asked


@pytest.mark.parametrize("distro", ["jazzy"])
def test_calls_made_at_once_with_no_daemon_are_answered_by_the_one_the_cold_call_starts(
    start_peer: Callable[..., RclpyPeer], cold_env: dict[str, str]
) -> None:
    for i in range(2):
        start_peer("--name", f"burst_{i}", "--talk", f"/burst_{i}")
    calls = [rostool_popen(["topic", "list"], cold_env) for _ in range(6)]
    answers = [(*call.communicate(timeout=60), call.returncode) for call in calls]
    for out, err, code in answers:
        assert (code, err) == (0, "")
        assert {"/burst_0", "/burst_1"} <= set(out.split())
    # one of them answered directly and started the daemon; the five others waited for it (each answering
    # directly would be one more participant: a burst of them fails past what the host's DDS can hold)
    assert daemon_status(cold_env).get("queries", 0) >= 5


def test_a_cold_call_whose_answer_is_an_error_still_starts_the_daemon(cold_env: dict[str, str]) -> None:
    done = rostool(["node", "info", "/nobody"], cold_env)
    assert done.returncode == 1 and len(done.stderr.splitlines()) == 1
    assert wait_until(lambda: daemon_status(cold_env)["running"] is True, timeout=30)


# Run in a process of its own (a DDS participant in the test worker would outlive the test): prints, as JSON,
# the node names of a direct DDS graph and, for each time ros_discovery_info's reader was made, what was
# known then: every remote participant seen, with the kinds (writer or reader) of its endpoints.
WATCH_READER = r"""
import json, sys
from rostool.graph.backends import open_ros2
from rostool.graph.ros2.discovery import GraphCache
made = []
defer = GraphCache.defer_info_reader
def watched(cache, make):
    def making():
        kinds = {key.hex(): set() for key in cache.participants if key != cache.own}
        for endpoint in cache.remote_endpoints():
            kinds.setdefault(endpoint.participant.hex(), set()).add(endpoint.is_writer)
        made.append({key: sorted(value) for key, value in kinds.items()})
        return make()
    defer(cache, making)
GraphCache.defer_info_reader = watched
_backend, graph = open_ros2("dds")
try:
    print(json.dumps({"nodes": graph.node_names(), "made": made}))
finally:
    graph.close()
"""

# With no other participant: when (seconds after discovery started) the reader was made.
EMPTY_DOMAIN = r"""
import json, time
from rostool.graph.ros2.discovery import INFO_READER_LATEST, start_discovery
cache = start_discovery()
made = []
cache.defer_info_reader(lambda: made.append(time.monotonic() - cache.started))
deadline = time.monotonic() + INFO_READER_LATEST + 10
while not made and time.monotonic() < deadline:
    cache.poll()
    time.sleep(0.05)
cache.participant.close()
print(json.dumps({"made": made, "latest": INFO_READER_LATEST}))
"""


def run_python(code: str, env: dict[str, str]) -> dict[str, Any]:
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)  # type: ignore[no-any-return]


@pytest.mark.parametrize("distro", ["jazzy", "kilted"])
def test_the_nodes_reader_is_made_once_every_participant_seen_described_itself(
    start_peer: Callable[..., RclpyPeer], graph_env: dict[str, str]
) -> None:
    for i in range(3):
        start_peer("--name", f"described_{i}", "--talk", f"/described_{i}")
    found = run_python(WATCH_READER, graph_env)
    assert found["nodes"] == ["/described_0", "/described_1", "/described_2"]
    assert len(found["made"]) == 1
    seen = found["made"][0]
    assert len(seen) >= 3  # the peers' participants were known when the reader was made...
    assert all(kinds == [False, True] for kinds in seen.values())  # ...each with its readers and writers


def test_with_no_participant_the_nodes_reader_is_made_at_the_latest(graph_env: dict[str, str]) -> None:
    found = run_python(EMPTY_DOMAIN, graph_env)
    assert len(found["made"]) == 1 and found["made"][0] >= found["latest"]  # nothing to wait for but the cap
