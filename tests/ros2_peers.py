"""Real ROS 2 peers for the tests: rclpy nodes of Jazzy and Kilted on Fast DDS, each distro in its own venv
that ./test.sh installs (ROSTOOL_PEERS_DIR, default ~/.cache/rostool/peers/<distro>).

Every peer runs loopback-only: a Fast DDS XML profile (UDPv4 only, interface whitelist 127.0.0.1, initial
peer 127.0.0.1, builtin transports off, so no multicast and no shared memory), and no
ROS_AUTOMATIC_DISCOVERY_RANGE in its environment (rmw_fastrtps's LOCALHOST mode would replace the
profile's transports and bind the other interfaces). `RclpyPeer.stop` checks the sockets it had open.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from tests.support import IN_CI, ros2_env, rostool, rostool_popen

if TYPE_CHECKING:
    from tests.netns import Machine

DISTROS = ("jazzy", "kilted")
PEER_SCRIPT = Path(__file__).resolve().parent / "rclpy_peer.py"
PEERS_DIR = Path(os.environ.get("ROSTOOL_PEERS_DIR") or Path.home() / ".cache" / "rostool" / "peers")

FASTDDS_PROFILE = """<?xml version="1.0" encoding="UTF-8"?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors>
    <transport_descriptor>
      <transport_id>loopback_udp</transport_id>
      <type>UDPv4</type>
      <interfaceWhiteList><address>127.0.0.1</address></interfaceWhiteList>
      <!-- initial peers reach participant indexes 0..N-1 on 127.0.0.1; Fast DDS's default of 4 leaves a
           newcomer blind to the fifth participant of a domain (a test's peers, ros2's daemon, rostool) -->
      <maxInitialPeersRange>32</maxInitialPeersRange>
    </transport_descriptor>
  </transport_descriptors>
  <participant profile_name="loopback_only" is_default_profile="true">
    <rtps>
      <userTransports><transport_id>loopback_udp</transport_id></userTransports>
      <useBuiltinTransports>false</useBuiltinTransports>
      <builtin>
        <metatrafficUnicastLocatorList>
          <locator><udpv4><address>127.0.0.1</address></udpv4></locator>
        </metatrafficUnicastLocatorList>
        <initialPeersList>
          <locator><udpv4><address>127.0.0.1</address></udpv4></locator>
        </initialPeersList>
      </builtin>
    </rtps>
  </participant>
</profiles>
"""


def peer_python(distro: str) -> Path:
    """The interpreter of a distro's peer venv; in CI its absence fails the test, elsewhere it skips."""
    python = PEERS_DIR / distro / "bin" / "python"
    if not python.exists():
        message = f"the {distro} rclpy peer venv is missing at {python.parent.parent}: run ./test.sh"
        if IN_CI:
            pytest.fail(message)
        pytest.skip(message)
    return python


# An rclpy node (a publisher on /NAME) that lives LIFE seconds from its context's start, then leaves cleanly:
# `python -c BRIEF_NODE NAME LIFE`; it prints "up" once its node exists
BRIEF_NODE = r"""
import sys, time
import rclpy
from std_msgs.msg import String
name, life = sys.argv[1], float(sys.argv[2])
context = rclpy.Context()
rclpy.init(context=context)
born = time.monotonic()
node = rclpy.create_node(name, context=context)
node.create_publisher(String, "/" + name, 10)
print("up", flush=True)
time.sleep(max(0.0, life - (time.monotonic() - born)))
node.destroy_node()
rclpy.shutdown(context=context)
"""


def fastdds_profile(lease: float | None = None) -> str:
    """The peers' loopback-only profile; `lease`: the participant's lease in seconds (Fast DDS's default
    is 20 s, announced every 3 s), announced 4 times per lease."""
    if lease is None:
        return FASTDDS_PROFILE
    every_ns = int(lease / 4 * 1e9)
    config = (
        f"<discovery_config><leaseDuration><sec>{int(lease)}</sec></leaseDuration><leaseAnnouncement>"
        f"<sec>{every_ns // 10**9}</sec><nanosec>{every_ns % 10**9}</nanosec></leaseAnnouncement>"
        "</discovery_config>"
    )
    return FASTDDS_PROFILE.replace("<builtin>", f"<builtin>\n        {config}", 1)


def peer_env(env: dict[str, str], tmp_path: Path, lease: float | None = None) -> dict[str, str]:
    """The peer's side of a test's ROS 2 environment: the same ROS_DOMAIN_ID, Fast DDS on loopback only
    (a participant lease of `lease` seconds, when given)."""
    profile = tmp_path / ("fastdds_loopback.xml" if lease is None else f"fastdds_loopback_lease{lease:g}.xml")
    if not profile.exists():
        # written whole, then renamed: peers started side by side never read half a profile
        partial = profile.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
        partial.write_text(fastdds_profile(lease))
        partial.replace(profile)
    hidden = ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOCALHOST_ONLY", "ROS_STATIC_PEERS", "CYCLONEDDS_URI",
              "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")  # fmt: skip
    clean = {k: v for k, v in env.items() if k not in hidden}
    home = tmp_path / "peer_ros_home"
    home.mkdir(exist_ok=True)
    clean.update(
        RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
        FASTRTPS_DEFAULT_PROFILES_FILE=str(profile),  # Fast DDS 2 (Jazzy)
        FASTDDS_DEFAULT_PROFILES_FILE=str(profile),  # Fast DDS 3 (Kilted)
        ROS_HOME=str(home),
        ROS_LOG_DIR=str(home / "log"),
        PYTHONUNBUFFERED="1",
    )
    return clean


def machine_peer_env(env: dict[str, str], tmp_path: Path) -> dict[str, str]:
    """A peer's environment on a private machine (tests/netns.py), where ROS's defaults are safe: `env`'s
    ROS settings (domain, range, static peers) kept, Fast DDS with no profile."""
    hidden = ("CYCLONEDDS_URI", "FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE",
              "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")  # fmt: skip
    clean = {k: v for k, v in env.items() if k not in hidden}
    home = tmp_path / "peer_ros_home"
    home.mkdir(exist_ok=True)
    clean.update(RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_HOME=str(home), ROS_LOG_DIR=str(home / "log"),
                 PYTHONUNBUFFERED="1")  # fmt: skip
    return clean


class RclpyPeer:
    """One running rclpy node (tests/rclpy_peer.py) and the JSON events it reported."""

    def __init__(
        self,
        distro: str,
        env: dict[str, str],
        tmp_path: Path,
        args: list[str],
        lease: float | None = None,
        on: Machine | None = None,
    ) -> None:
        """`on`: a private machine (tests/netns.py) to run on, with ROS's defaults and `env`'s ROS settings
        instead of the loopback-only profile."""
        self.distro = distro
        self.events: list[dict[str, Any]] = []
        self._changed = threading.Condition()
        command = [str(peer_python(distro)), str(PEER_SCRIPT), *args]
        self.proc = subprocess.Popen(
            on.command(command) if on else command,
            env=machine_peer_env(env, tmp_path) if on else peer_env(env, tmp_path, lease),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self._stderr: list[str] = []
        threading.Thread(target=self._read_stdout, daemon=True).start()
        threading.Thread(target=self._read_stderr, daemon=True).start()

    def _read_stdout(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            try:
                event = json.loads(line)
            except ValueError:
                continue
            with self._changed:
                self.events.append(event)
                self._changed.notify_all()

    def _read_stderr(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self._stderr.append(line)

    @property
    def stderr(self) -> str:
        return "".join(self._stderr)

    def of(self, kind: str) -> list[dict[str, Any]]:
        with self._changed:
            return [e for e in self.events if e["event"] == kind]

    def wait_for(
        self, kind: str, where: Callable[[dict[str, Any]], bool] = lambda _e: True, timeout: float = 15.0
    ) -> dict[str, Any]:
        """The first `kind` event (already seen or still to come) that `where` accepts."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                for event in self.events:
                    if event["event"] == kind and where(event):
                        return event
                left = deadline - time.monotonic()
                if left <= 0 or self.proc.poll() is not None:
                    raise AssertionError(
                        f"{self.distro} peer: no {kind!r} event within {timeout} s "
                        f"(exit {self.proc.poll()}); stderr: {self.stderr[-2000:]}"
                    )
                self._changed.wait(min(left, 0.2))

    def bound_addresses(self) -> list[str]:
        """Local addresses of the UDP and TCP sockets the peer has open (from `ss`)."""
        found = []
        for proto in ("-uanp", "-tanp"):
            out = subprocess.run(["ss", proto], capture_output=True, text=True).stdout
            for line in out.splitlines():
                if f"pid={self.proc.pid}," in line:
                    found.append(line.split()[3])
        return found

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(2)
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def assert_loopback_only(addresses: list[str]) -> None:
    loopback = re.compile(r"^(127\.[\d.]+|\[::1\]|\[::ffff:127\.[\d.]+\]):")
    outside = [a for a in addresses if not loopback.match(a)]
    assert not outside, f"a peer bound a non-loopback address: {outside}"


@pytest.fixture(params=DISTROS)
def distro(request: pytest.FixtureRequest) -> str:
    peer_python(request.param)
    return str(request.param)


@pytest.fixture
def graph_env() -> dict[str, str]:
    """rostool's environment for one test's ROS 2 graph (its own domain, loopback only)."""
    return ros2_env()


def held_locks(run_dir: Path) -> list[int]:
    """The pids of rostool graph daemons still holding a lock in the runtime directory `run_dir` (-1: a
    holder that wrote no pid)."""
    held = []
    for lock in run_dir.glob("rostool/*.lock"):
        with open(lock, encoding="utf-8") as handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:
                text = handle.read().strip()
                held.append(int(text) if text.isdigit() else -1)
    return held


class WarmDaemon:
    """rostool's graph daemon for one test's graph, as a user runs every verb by default: `env` is the
    test's environment with the daemon allowed, in a runtime directory of its own (a short path: a Unix
    socket's is limited to 107 bytes). The daemon starts at once and discovers while the peers start;
    `ready()` waits until it answers, so that every listing of the test is served warm."""

    def __init__(
        self,
        env: dict[str, str],
        popen: Callable[[list[str], dict[str, str]], subprocess.Popen[str]] | None = None,
    ) -> None:
        """`popen(args, env)` runs rostool as the test runs it (default: the DDS backend of the test venv;
        the daemon's key includes the backend and the interpreter)."""
        self.run_dir = Path(tempfile.mkdtemp(prefix="rtw"))
        self.env = {**env, "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(self.run_dir),
                    "XDG_STATE_HOME": str(self.run_dir / "state")}  # fmt: skip
        self._popen = popen or (lambda args, env: rostool_popen(["--ros2", *args], env))
        # --idle: a daemon whose test was killed before its teardown does not hold the domain for hours
        starting = self._popen(["daemon", "start", "--idle", "300"], self.env)
        self._starting: subprocess.Popen[str] | None = starting

    def ready(self) -> None:
        if self._starting is None:
            return
        out, err = self._starting.communicate(timeout=60)
        self._starting = None
        assert "The daemon has been started" in out or "already running" in out, f"daemon start: {out}{err}"

    def status(self) -> dict[str, Any]:
        """The daemon's status (`daemon status --json`'s object), asked on its socket from this process: a
        `daemon status --json` run per poll cost a Python start-up each."""
        from rostool.graph.daemon.client import DaemonClient
        from rostool.graph.daemon.place import DaemonPlace

        sockets = list(self.run_dir.glob("rostool/*.sock"))
        assert len(sockets) == 1, f"one daemon socket expected in {self.run_dir}: {sockets}"
        (path,) = sockets
        place = DaemonPlace(path.stem, path, path.with_suffix(".lock"), path.with_suffix(".log"), ())
        found = DaemonClient("auto", self.env, place).status()
        assert found is not None, f"no daemon answers on {path}"
        return found

    def graph_size(self) -> dict[str, int]:
        """What the daemon holds now (its status's graph: nodes, topics, services, actions)."""
        return dict(self.status()["graph"])

    def held_locks(self) -> list[int]:
        """The pids of daemons still holding a lock in the runtime directory."""
        return held_locks(self.run_dir)

    def stop(self) -> list[int]:
        """Stop every daemon of the runtime directory; the pids that had to be killed."""
        if self._starting is not None:
            self._starting.wait(timeout=60)
        rostool(["daemon", "stop", "--all"], self.env)
        left = [pid for pid in self.held_locks() if pid > 0]
        for pid in left:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(self.run_dir, ignore_errors=True)
        return left


@contextlib.contextmanager
def serving(env: dict[str, str]) -> Iterator[WarmDaemon]:
    """A WarmDaemon of `env`, stopped at the end; no daemon may be left running."""
    daemon = WarmDaemon(env)
    yield daemon
    left = daemon.stop()
    assert not left, f"graph daemons still running after `daemon stop --all`: {left}"


@pytest.fixture
def warm_daemon(graph_env: dict[str, str]) -> Iterator[WarmDaemon]:
    """The test's graph served by a graph daemon of its own (see WarmDaemon), stopped at the end."""
    with serving(graph_env) as daemon:
        yield daemon


class StartPeer:
    """start_peer("--talk", "/chatter", ...) runs a real rclpy node of the test's distro in the test's
    domain and returns it ready; `start_peer.together([...], [...])` starts several side by side (a peer's
    start-up is mostly waiting: 0.8 s idle, 3-4 s under load) and returns them all ready. `lease=S`: the
    peers' participant lease (Fast DDS's default: 20 s), for tests that wait for one to expire."""

    def __init__(self, distro: str, env: dict[str, str], tmp_path: Path) -> None:
        self.distro, self.env, self.tmp_path = distro, env, tmp_path
        self.peers: list[RclpyPeer] = []

    def __call__(self, *args: str, lease: float | None = None) -> RclpyPeer:
        (peer,) = self.together(list(args), lease=lease)
        return peer

    def together(self, *arg_lists: list[str], lease: float | None = None) -> list[RclpyPeer]:
        started = [RclpyPeer(self.distro, self.env, self.tmp_path, args, lease) for args in arg_lists]
        self.peers += started
        for peer in started:
            peer.wait_for("ready", timeout=30)
        return started

    def stop_all(self) -> None:
        """Stop every peer; each must have bound loopback addresses only."""
        addresses = []
        for peer in self.peers:
            addresses += peer.bound_addresses()
            peer.stop()
        assert_loopback_only(addresses)


@pytest.fixture
def start_peer(distro: str, graph_env: dict[str, str], tmp_path: Path) -> Iterator[StartPeer]:
    """Real rclpy nodes of the test's distro in the test's domain (StartPeer); every peer is stopped at the
    end and must have bound loopback only."""
    start = StartPeer(distro, graph_env, tmp_path)
    yield start
    start.stop_all()


def rclpy_command(args: list[str], distro: str) -> list[str]:
    """rostool on its rclpy backend, in the distro's peer venv (where test.sh installs it too)."""
    return [str(peer_python(distro)), "-m", "rostool", "--ros2-backend", "rclpy", *args]


def rostool_rclpy(
    args: list[str], env: dict[str, str], tmp_path: Path, distro: str, timeout: float = 30
) -> subprocess.CompletedProcess[str]:
    """Run rostool's rclpy backend as the peers run: the test's domain, Fast DDS on loopback only."""
    return subprocess.run(
        rclpy_command(args, distro),
        env=peer_env(env, tmp_path),
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def rostool_rclpy_popen(
    args: list[str], env: dict[str, str], tmp_path: Path, distro: str
) -> subprocess.Popen[str]:
    return subprocess.Popen(
        rclpy_command(args, distro),
        env=peer_env(env, tmp_path),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def bound_addresses(pid: int) -> list[str]:
    """Local addresses of the UDP and TCP sockets process `pid` has open (from `ss`)."""
    found = []
    for proto in ("-uanp", "-tanp"):
        out = subprocess.run(["ss", proto], capture_output=True, text=True).stdout
        found += [line.split()[3] for line in out.splitlines() if f"pid={pid}," in line]
    return found
