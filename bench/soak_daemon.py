"""The graph daemon's memory under churn: real rclpy nodes join and leave every second for MINUTES, while
the daemon answers; its RSS is sampled all along (issue 21: "daemon RSS flat over 10 minutes").

    .venv/bin/python bench/soak_daemon.py [--minutes 10] [--backend dds|rclpy]...

One churner process (the Jazzy peer venv, Fast DDS on loopback) starts a new rclpy context (a DDS
participant of its own) every second with one node, a publisher, a subscription and a service on names
never used before, and shuts the oldest down once ALIVE are up: every second one participant joins and one
leaves cleanly, and every GID, topic and node name is new. Every SAMPLE seconds `rostool daemon status
--json` (a new process, as a user's) gives the daemon's pid and graph size; RSS is read from /proc. The
graph never holds more than the steady node, ALIVE churned nodes and one joining or leaving: a larger
count would be a node the daemon keeps after it left (stale), printed at the end.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from _graph import VENV_PYTHON, ros2_env

from tests.ros2_peers import PEERS_DIR, RclpyPeer, peer_env

DISTRO = "jazzy"
ALIVE = 3
SAMPLE = 5.0
WARMUP = 30.0  # seconds before the first RSS counts (the daemon's first queries allocate once)

CHURNER = r"""
import json, signal, sys, time
import rclpy
from std_msgs.msg import String
from std_srvs.srv import Trigger
period, alive = float(sys.argv[1]), int(sys.argv[2])
signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
up = []
k = 0
next_at = time.monotonic()
try:
    while True:
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node(f"churn_{k}", context=context)
        node.create_publisher(String, f"/churn_{k}", 10)
        node.create_subscription(String, f"/churn_in_{k}", lambda _m: None, 10)
        node.create_service(Trigger, f"/churn_srv_{k}", lambda _r, s: s)
        up.append((context, node))
        print(json.dumps({"event": "joined", "k": k}), flush=True)
        k += 1
        if len(up) > alive:
            old_context, old_node = up.pop(0)
            old_node.destroy_node()
            rclpy.shutdown(context=old_context)
        next_at += period
        time.sleep(max(0.0, next_at - time.monotonic()))
finally:
    for context, node in up:
        node.destroy_node()
        rclpy.shutdown(context=context)
"""


def rss_kib(pid: int) -> int:
    with open(f"/proc/{pid}/status", encoding="utf-8") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


@contextlib.contextmanager
def churning(env: dict[str, str], scratch: Path) -> Iterator[None]:
    """The steady node and the churner (see the module's docstring) running; both stopped at the end."""
    steady = RclpyPeer(DISTRO, env, scratch, ["--name", "steady", "--talk", "/steady"])
    try:
        steady.wait_for("ready", timeout=60)
        churner = subprocess.Popen(
            [str(PEERS_DIR / DISTRO / "bin" / "python"), "-c", CHURNER, "1.0", str(ALIVE)],
            env=peer_env(env, scratch), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        try:
            yield
        finally:
            churner.terminate()  # rclpy keeps SIGINT for its contexts
            try:
                churner.wait(timeout=10)
            except subprocess.TimeoutExpired:
                churner.kill()
                churner.wait()
    finally:
        steady.stop()


def _sample(
    command: list[str], tool_env: dict[str, str], minutes: float, samples: list[tuple[float, int, int]],
    pids: set[int],
) -> None:
    """The daemon's RSS and node count every SAMPLE seconds for `minutes`."""
    start = time.monotonic()
    while time.monotonic() - start < minutes * 60:
        time.sleep(SAMPLE)
        done = subprocess.run(
            [*command, "daemon", "status", "--json"], env=tool_env, capture_output=True, text=True,
            timeout=60,
        )  # fmt: skip
        status = json.loads(done.stdout)
        if not status.get("running"):
            print(f"  {time.monotonic() - start:6.0f} s: the daemon is not running")
            continue
        pid = int(status["pid"])
        pids.add(pid)
        nodes = int(status["graph"]["nodes"])
        samples.append((time.monotonic() - start, rss_kib(pid), nodes))
        if len(samples) % 12 == 0:
            print(f"  {samples[-1][0]:6.0f} s: RSS {samples[-1][1] / 1024:.1f} MiB, {nodes} nodes")


def soak(backend: str, minutes: float, env: dict[str, str], scratch: Path) -> None:
    fast = peer_env(env, scratch)
    if backend == "dds":
        command, tool_env = [VENV_PYTHON, "-m", "rostool", "--ros2-backend", "dds"], env
    else:
        python = str(PEERS_DIR / DISTRO / "bin" / "python")
        command, tool_env = [python, "-m", "rostool", "--ros2-backend", "rclpy"], fast
    subprocess.run([*command, "daemon", "start"], env=tool_env, check=True, capture_output=True, timeout=60)
    samples: list[tuple[float, int, int]] = []  # (seconds, RSS KiB, nodes)
    pids: set[int] = set()
    try:
        with churning(env, scratch):
            _sample(command, tool_env, minutes, samples, pids)
    finally:
        subprocess.run([*command, "daemon", "stop"], env=tool_env, capture_output=True, timeout=60)
    counted = [s for s in samples if s[0] >= WARMUP]
    first, last = counted[0], counted[-1]
    peak = max(counted, key=lambda s: s[1])
    stale = [s for s in samples if s[2] > 1 + ALIVE + 1]
    print(f"| {backend} | {minutes:g} min | {first[1] / 1024:.1f} MiB at {first[0]:.0f} s | "
          f"{last[1] / 1024:.1f} MiB at {last[0]:.0f} s | {peak[1] / 1024:.1f} MiB at {peak[0]:.0f} s | "
          f"{min(s[2] for s in samples)}-{max(s[2] for s in samples)} | {len(stale)}/{len(samples)} | "
          f"{len(pids)} |")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--backend", action="append", choices=("dds", "rclpy"))
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    print(
        "| backend | churn | RSS first (after warm-up) | RSS last | RSS max | nodes seen | over the "
        "bound (stale) | daemon pids |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for backend in args.backend or ["dds", "rclpy"]:
        scratch = Path(tempfile.mkdtemp(prefix="rts"))
        run_dir = scratch / "run"
        run_dir.mkdir(mode=0o700)
        env = {**ros2_env(), "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(run_dir),
               "XDG_STATE_HOME": str(scratch / "state"), "ROSTOOL_DAEMON_BUILD": "soak"}  # fmt: skip
        try:
            soak(backend, args.minutes, env, scratch)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
    print(f"load average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
