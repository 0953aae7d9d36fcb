"""Shared pieces of the live-graph benchmarks: a loopback master, a counted publisher, process timing."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
VENV_PYTHON = str(ROOT / ".venv" / "bin" / "python")
sys.path.insert(0, str(ROOT))

# The benchmarks use the tests' loopback helpers, so both start peers the same way.
from tests.support import debian_env, free_port, ros1_env, ros2_env  # noqa: E402

__all__ = ["debian_env", "free_port", "ros1_env", "ros2_env"]


def loopback_env(port: int) -> dict[str, str]:
    return ros1_env(port, Path("/tmp/rostool-bench-ros"))


def start_master(env: dict[str, str]) -> subprocess.Popen[bytes]:
    port = env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = subprocess.Popen(["rosmaster", "--core", "-p", port], env=debian_env(env),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", int(port)), timeout=0.2).close()
            return proc
        except OSError:
            time.sleep(0.05)
    raise SystemExit("rosmaster did not start")


# Publishes exactly COUNT messages of TYPE (Int32 counting up, else a fixed sample) at RATE (0: as fast
# as possible) once SUBS subscribers are connected, then prints "sent N in S seconds". Uses rostool's own
# client, so the count is exact.
PUBLISHER = r"""
import sys, time, struct
from rostool.graph.ros1.node import Node
from rostool.interfaces.ros1 import TypeRegistry
count, rate, subs, type_name = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
msg_type = TypeRegistry().builtin(type_name)
if type_name != "std_msgs/Int32":
    from rostool.interfaces.fill import build_message
    sample = build_message(msg_type.store, msg_type.store_name, {
        "header": {"seq": 7, "stamp": {"secs": 1700000000, "nsecs": 123456789}, "frame_id": "map"},
        "pose": {"position": {"x": 1.5, "y": -2.25, "z": 0.1}, "orientation": {"w": 1.0}}})
    fixed = msg_type.serialize(sample)
with Node("bench_pub", anonymous=False) as node:
    pub = node.advertise("/bench", msg_type)
    if not pub.wait_for_subscribers(subs, 30):
        sys.exit("subscribers did not connect")
    time.sleep(1.0)
    period = 1.0 / rate if rate else 0.0
    start = time.perf_counter()
    for i in range(count):
        if period:
            delay = start + i * period - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
        pub.publish_raw(struct.pack("<i", i) if type_name == "std_msgs/Int32" else fixed)
    elapsed = time.perf_counter() - start
    print(f"sent {count} in {elapsed:.6f} seconds", flush=True)
    try:
        time.sleep(3.0)
    except KeyboardInterrupt:
        pass
"""


def start_publisher(
    env: dict[str, str], count: int, rate: float, subscribers: int, type_name: str = "std_msgs/Int32"
) -> subprocess.Popen[str]:
    args = [VENV_PYTHON, "-c", PUBLISHER, str(count), str(rate), str(subscribers), type_name]
    return subprocess.Popen(args, env=env, stdout=subprocess.PIPE, text=True)


def rostool_cmd(*args: str) -> list[str]:
    return [VENV_PYTHON, "-m", "rostool", *args]


def cpu_seconds(pid: int) -> float:
    """User+system CPU a running process has used so far (from /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def median_wall(cmd: Sequence[str], env: dict[str, str], runs: int = 9) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(list(cmd), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times.append(time.perf_counter() - start)
    return sorted(times)[len(times) // 2]


def wait_subscribed(env: dict[str, str], topic: str, count: int, timeout: float = 20) -> None:
    import xmlrpc.client

    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        _code, _msg, (_pubs, subs, _srvs) = master.getSystemState("/bench")
        nodes = next((n for t, n in subs if t == topic), [])
        if len(nodes) >= count:
            return
        time.sleep(0.1)
    sys.exit(f"only some subscribers of {topic} registered")


def tear_down_ros2(env: dict[str, str], ros2_env: dict[str, str], ros2: str, peers: Sequence[Any],
                   scratch: Path) -> None:  # fmt: skip
    """The end of a ROS 2 bench: every rostool daemon and the real ros2's daemon stopped, then the peers
    (tests.ros2_peers.RclpyPeer), each checked to have bound loopback only, and the scratch folder."""
    import shutil

    from tests.ros2_peers import assert_loopback_only

    subprocess.run([VENV_PYTHON, "-m", "rostool", "daemon", "stop", "--all"], env=env, capture_output=True,
                   timeout=60)  # fmt: skip
    subprocess.run([ros2, "daemon", "stop"], env=ros2_env, capture_output=True, timeout=60)
    for peer in peers:
        addresses = peer.bound_addresses()
        peer.stop()
        assert_loopback_only(addresses)
    shutil.rmtree(scratch, ignore_errors=True)
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
