"""Private machines for the across-machines tests: Linux network namespaces joined by veth pairs
(CONTRIBUTING, "Network rule"). None of them is the host's own namespace, so ROS's defaults (multicast,
SUBNET discovery, 0.0.0.0) are safe inside them; addresses come from 198.18.0.0/15, the range set aside
for benchmarking.

    laptop 198.18.1.10 ─┐
    robot  198.18.1.20 ─┼─ lan (a bridge) ─ router 198.18.1.1 │ 198.18.2.1 ─ far 198.18.2.20
                        ┘

The laptop and the robot share one subnet (a Wi-Fi network); the far robot is behind the router (forwarding
on, no multicast routing: only unicast crosses it). Each machine has its own host name (in its own UTS
namespace), its own /etc/hosts in Debian's default form (the host name on 127.0.1.1, so it resolves to
loopback, as on a fresh Debian machine) and its own /etc/machine-id (Fast DDS tells hosts apart by it), both
bind-mounted by `ip netns exec` from /etc/netns/<namespace>/. Namespaces are named `rt<pid>-<n>`, so xdist
workers never share one; leftovers of a dead run are removed at the next start.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import uuid
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from tests.support import IN_CI

NETNS_RUN = Path("/var/run/netns")
NETNS_ETC = Path("/etc/netns")
LAN = "198.18.1"
FAR = "198.18.2"
SILENT = "198.18.9"  # routed to the router, which drops it silently


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["ip", *args], capture_output=True, text=True, check=check)


def netns_missing() -> str | None:
    """Why private machines cannot be made here, or None."""
    if shutil.which("ip") is None:
        return "iproute2's `ip` is missing"
    if os.geteuid() != 0:
        return "network namespaces need root"
    probe = f"rt{os.getpid()}-probe"
    made = _ip("netns", "add", probe, check=False)
    if made.returncode != 0:
        return f"`ip netns add` failed: {made.stderr.strip()}"
    _ip("netns", "del", probe, check=False)
    return None


def require_netns() -> None:
    """Skip outside CI when network namespaces cannot be made; in CI that is a failure."""
    reason = netns_missing()
    if reason:
        if IN_CI:
            pytest.fail(f"private machines (network namespaces) are needed in CI: {reason}")
        pytest.skip(reason)


def remove_leftovers() -> None:
    """Namespaces (and their /etc/netns files) of runs whose process is gone."""
    if not NETNS_RUN.is_dir():
        return
    for entry in NETNS_RUN.iterdir():
        name = entry.name
        if not name.startswith("rt") or "-" not in name:
            continue
        pid = name[2:].split("-", 1)[0]
        if pid.isdigit() and not Path(f"/proc/{pid}").exists():
            _ip("netns", "del", name, check=False)
            shutil.rmtree(NETNS_ETC / name, ignore_errors=True)


@dataclass
class Machine:
    """One private machine: a network namespace with its own host name, /etc/hosts and machine id."""

    name: str  # the host name, e.g. "laptop"
    namespace: str
    address: str  # its address on its one link ("" for the lan switch)
    interface: str = "eth0"

    def command(self, argv: Sequence[str]) -> list[str]:
        """`argv` run on this machine (its network, host name and /etc files)."""
        return ["ip", "netns", "exec", self.namespace, "unshare", "--uts", "sh", "-c",
                'hostname "$0" && exec "$@"', self.name, *argv]  # fmt: skip

    def popen(self, argv: Sequence[str], env: dict[str, str], **kwargs: object) -> subprocess.Popen[str]:
        options: dict[str, object] = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True}
        options.update(kwargs)
        return subprocess.Popen(self.command(argv), env=env, **options)  # type: ignore[call-overload]

    def run(
        self, argv: Sequence[str], env: dict[str, str], timeout: float = 30, input: str | None = None
    ) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            self.command(argv), env=env, capture_output=True, text=True, timeout=timeout, input=input
        )



@dataclass
class PrivateNetwork:
    """A laptop and a robot on one subnet, and a far robot behind a router."""

    tag: str
    made: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.lan = Machine("lan", f"{self.tag}-lan", "")
        self.laptop = Machine("laptop", f"{self.tag}-laptop", f"{LAN}.10")
        self.robot = Machine("robot", f"{self.tag}-robot", f"{LAN}.20")
        self.router = Machine("router", f"{self.tag}-router", f"{LAN}.1")
        self.far = Machine("far", f"{self.tag}-far", f"{FAR}.20")
        try:
            self._build()
        except BaseException:
            self.close()
            raise

    def _machine(self, machine: Machine) -> None:
        _ip("netns", "add", machine.namespace)
        self.made.append(machine.namespace)
        _ip("-n", machine.namespace, "link", "set", "lo", "up")
        etc = NETNS_ETC / machine.namespace
        etc.mkdir(parents=True, exist_ok=True)
        # Debian's default: the host name on 127.0.1.1, so a node's own name resolves to loopback
        (etc / "hosts").write_text(f"127.0.0.1\tlocalhost\n127.0.1.1\t{machine.name}\n")
        (etc / "machine-id").write_text(uuid.uuid4().hex + "\n")

    def _cable(self, a: Machine, a_if: str, b: Machine, b_if: str) -> None:
        _ip("-n", a.namespace, "link", "add", a_if, "type", "veth", "peer", "name", b_if,
            "netns", b.namespace)  # fmt: skip
        _ip("-n", a.namespace, "link", "set", a_if, "up")
        _ip("-n", b.namespace, "link", "set", b_if, "up")

    def _build(self) -> None:
        for machine in (self.lan, self.laptop, self.robot, self.router, self.far):
            self._machine(machine)
        _ip("-n", self.lan.namespace, "link", "add", "br0", "type", "bridge")
        _ip("-n", self.lan.namespace, "link", "set", "br0", "up")
        for machine, port in ((self.laptop, "p-laptop"), (self.robot, "p-robot"), (self.router, "p-router")):
            self._cable(machine, "eth0", self.lan, port)
            _ip("-n", self.lan.namespace, "link", "set", port, "master", "br0")
        self._cable(self.router, "eth1", self.far, "eth0")
        for machine in (self.laptop, self.robot, self.router, self.far):
            _ip("-n", machine.namespace, "addr", "add", f"{machine.address}/24", "dev", "eth0")
        _ip("-n", self.router.namespace, "addr", "add", f"{FAR}.1/24", "dev", "eth1")
        for machine, gateway in ((self.laptop, f"{LAN}.1"), (self.robot, f"{LAN}.1"), (self.far, f"{FAR}.1")):
            _ip("-n", machine.namespace, "route", "add", "default", "via", gateway)
        # behind the router, a network that swallows everything without a word (a VPN that is down)
        _ip("-n", self.router.namespace, "route", "add", "blackhole", f"{SILENT}.0/24")
        subprocess.run(
            ["ip", "netns", "exec", self.router.namespace, "sysctl", "-qw", "net.ipv4.ip_forward=1"],
            check=True, capture_output=True,
        )  # fmt: skip

    def link(self, machine: Machine, up: bool) -> None:
        """Drop or restore `machine`'s link at the switch, as a Wi-Fi link drops: its own interface and
        routes stay, nothing passes meanwhile."""
        _ip("-n", self.lan.namespace, "link", "set", f"p-{machine.name}", "up" if up else "down")

    def close(self) -> None:
        for namespace in reversed(self.made):
            _ip("netns", "del", namespace, check=False)
            shutil.rmtree(NETNS_ETC / namespace, ignore_errors=True)
        self.made.clear()


_made = 0


@contextlib.contextmanager
def private_network() -> Iterator[PrivateNetwork]:
    global _made
    require_netns()
    remove_leftovers()
    _made += 1
    network = PrivateNetwork(f"rt{os.getpid()}-{_made}")
    try:
        yield network
    finally:
        network.close()


@pytest.fixture(scope="module")
def network() -> Iterator[PrivateNetwork]:
    """The private machines, shared by one test module (registered as a plugin in conftest)."""
    with private_network() as made:
        yield made


def user_env(**settings: str) -> dict[str, str]:
    """A user's shell on a private machine: no ROS variable but `settings`; rostool answers directly."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS") and k != "CYCLONEDDS_URI"}
    env.update(PYTHONUNBUFFERED="1", ROSTOOL_NO_DAEMON="1", **settings)
    return env
