"""The graph daemon's RSS under churn, in two graphs side by side (issue 21: "daemon RSS flat over 10
minutes of nodes joining and leaving every second"): in one, every churned node, topic and service has a
name never used before (soak_daemon.py's churn); in the other, the same churn cycles through REUSE names
(nodes restarting under their names, as a real system's do). Both run at once, so the machine's load is
the same for both.

    .venv/bin/python bench/bench_daemon_rss.py [--minutes 10] [--backend dds|rclpy] [--reuse 12]

Each graph has its own domain, a steady node, a churner (a new rclpy context, i.e. a DDS participant,
every second with a node, a publisher, a subscription and a service; the oldest of ALIVE leaves) and a
graph daemon started as `rostool` starts it. Every SAMPLE seconds each daemon's RSS is read from /proc
and its node count from `daemon status --json`. The slope is a least-squares fit of RSS over the samples
after WARMUP seconds (the tables of a graph of this size fill in the first minute or two).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from _graph import VENV_PYTHON, ros2_env
from soak_daemon import ALIVE, CHURNER, DISTRO, rss_kib

from tests.ros2_peers import PEERS_DIR, RclpyPeer, peer_env

SAMPLE = 5.0
WARMUP = 120.0


def churner_code(reuse: int) -> str:
    """soak_daemon's churner; with `reuse`, its node, topic and service names cycle through `reuse` values
    instead of being new every second."""
    if not reuse:
        return CHURNER
    code = CHURNER.replace('_{k}"', '_{k % REUSE}"')
    return code.replace("up = []", f"up = []\nREUSE = {reuse}")


def status(command: list[str], env: dict[str, str]) -> dict[str, object]:
    done = subprocess.run([*command, "daemon", "status", "--json"], env=env, capture_output=True, text=True,
                          timeout=60)  # fmt: skip
    found = json.loads(done.stdout or "{}")
    return found if isinstance(found, dict) else {}


def slope_mib_per_min(rows: list[tuple[float, int, int, int]], column: int = 1) -> float:
    late = [(row[0], row[column] / 1024) for row in rows if row[0] >= WARMUP]
    if len(late) < 2:
        return float("nan")
    mean_t = sum(t for t, _ in late) / len(late)
    mean_r = sum(r for _, r in late) / len(late)
    num = sum((t - mean_t) * (r - mean_r) for t, r in late)
    den = sum((t - mean_t) ** 2 for t, _ in late)
    return num / den * 60


class Churned:
    """One graph: its environment, daemon, steady node and churner."""

    def __init__(self, label: str, reuse: int, backend: str, scratch: Path) -> None:
        self.label = label
        folder = scratch / label
        (folder / "run").mkdir(parents=True, mode=0o700)
        self.env = {**ros2_env(), "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(folder / "run"),
                    "XDG_STATE_HOME": str(folder / "state"), "ROSTOOL_DAEMON_BUILD": "rss"}  # fmt: skip
        self.fast = peer_env(self.env, folder)
        python = VENV_PYTHON if backend == "dds" else str(PEERS_DIR / DISTRO / "bin" / "python")
        self.tool_env = self.env if backend == "dds" else self.fast
        self.command = [python, "-m", "rostool", "--ros2-backend", backend]
        subprocess.run([*self.command, "daemon", "start"], env=self.tool_env, check=True, capture_output=True,
                       timeout=60)  # fmt: skip
        self.pid = int(str(status(self.command, self.tool_env)["pid"]))
        self.steady = RclpyPeer(DISTRO, self.env, folder, ["--name", "steady", "--talk", "/steady"])
        self.steady.wait_for("ready", timeout=60)
        self.churner = subprocess.Popen(
            [str(PEERS_DIR / DISTRO / "bin" / "python"), "-c", churner_code(reuse), "1.0", str(ALIVE)],
            env=self.fast, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        self.rows: list[tuple[float, int, int, int]] = []  # seconds, RSS, nodes, malloc in use (KiB)

    def sample(self, seconds: float) -> str:
        found = status(self.command, self.tool_env)
        graph, memory = found.get("graph"), found.get("memory")
        nodes = int(graph.get("nodes", -1)) if isinstance(graph, dict) else -1
        in_use = int(memory.get("malloc_in_use_kib", -1)) if isinstance(memory, dict) else -1
        self.rows.append((seconds, rss_kib(self.pid), nodes, in_use))
        return f"{self.rows[-1][1] / 1024:.2f}, {in_use / 1024:.2f}, {nodes}"

    def stop(self) -> None:
        self.churner.terminate()  # rclpy keeps SIGINT for its contexts
        try:
            self.churner.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.churner.kill()
            self.churner.wait()
        self.steady.stop()
        subprocess.run([*self.command, "daemon", "stop"], env=self.tool_env, capture_output=True, timeout=60)

    def summary(self) -> str:
        rows = self.rows
        late = [row for row in rows if row[0] >= 60] or rows
        at2 = min(rows, key=lambda row: abs(row[0] - WARMUP))
        peak, nodes = max(r[1] for r in rows) / 1024, f"{min(r[2] for r in rows)}-{max(r[2] for r in rows)}"
        return (f"| {self.label} | {late[0][1] / 1024:.2f} MiB | {at2[1] / 1024:.2f} MiB | "
                f"{rows[-1][1] / 1024:.2f} MiB at {rows[-1][0]:.0f} s | {peak:.2f} MiB | "
                f"{slope_mib_per_min(rows):+.3f} | {at2[3] / 1024:.2f} -> {rows[-1][3] / 1024:.2f} MiB, "
                f"{slope_mib_per_min(rows, 3):+.3f} | {nodes} |")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--backend", choices=("dds", "rclpy"), default="dds")
    parser.add_argument("--reuse", type=int, default=12, help="names the second graph's churn cycles through")
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="rtr"))
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    graphs: list[Churned] = []
    try:
        graphs.append(Churned("new names", 0, args.backend, scratch))
        graphs.append(Churned(f"{args.reuse} names reused", args.reuse, args.backend, scratch))
        start = time.monotonic()
        heads = [f"{graph.label}: RSS, malloc in use (MiB), nodes" for graph in graphs]
        print("| s | " + " | ".join(heads) + " |")
        while time.monotonic() - start < args.minutes * 60:
            time.sleep(SAMPLE)
            cells = [graph.sample(time.monotonic() - start) for graph in graphs]
            if len(graphs[0].rows) % 6 == 0:
                print(f"| {time.monotonic() - start:.0f} | " + " | ".join(cells) + " |", flush=True)
        print(f"\n{args.backend} daemon | RSS at 1 min | at {WARMUP:.0f} s | last | max | slope after "
              f"{WARMUP:.0f} s (MiB/min) | "
              f"malloc in use: {WARMUP:.0f} s -> last, slope | nodes |")  # fmt: skip
        print("|---|---|---|---|---|---|---|---|")
        for graph in graphs:
            print(graph.summary())
    finally:
        for graph in graphs:
            graph.stop()
        shutil.rmtree(scratch, ignore_errors=True)
        print(f"load average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
