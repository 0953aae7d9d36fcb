"""CPU seconds per test, of every process the test started (rostool runs, `ros2`, rclpy peers, Debian's ROS 1
tools, graph daemons that detach), measured by the kernel: each test runs in a cpuacct cgroup of its own
(cgroup v1, root only), which its processes inherit at fork, also when they detach or outlive the test.

    ROSTOOL_TEST_CPU=/tmp/cpu ./test.sh ...      # writes /tmp/cpu/<worker>.jsonl, one line per test
    .venv/bin/python -m tests.cpu_profile /tmp/cpu [N]   # CPU and wall per module; the N costliest tests

The CPU of the test process itself (fixtures, in-process calls, pytest) counts too, while the test runs.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import threading
import time
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

CPUACCT = Path("/sys/fs/cgroup/cpuacct")


class CpuProfile:
    def __init__(self, out_dir: Path) -> None:
        self.out_dir = out_dir
        self.worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        self.root = CPUACCT / f"rostool-tests-{os.getpid()}"
        self.root.mkdir()
        self.home = self._own_cgroup()
        self.tests: list[dict[str, object]] = []

    @staticmethod
    def _own_cgroup() -> Path:
        for line in Path("/proc/self/cgroup").read_text().splitlines():
            _id, controllers, path = line.split(":", 2)
            if "cpuacct" in controllers.split(","):
                return CPUACCT / path.lstrip("/")
        return CPUACCT

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item) -> Iterator[None]:
        group = self.root / str(len(self.tests))
        (group / "pytest").mkdir(parents=True)
        (group / "pytest" / "cgroup.procs").write_text(str(os.getpid()))
        sorter = KindSorter(group)
        start = time.monotonic()
        try:
            yield
        finally:
            (self.home / "cgroup.procs").write_text(str(os.getpid()))
            sorter.stop()
            wall = time.monotonic() - start
            self.tests.append({"test": item.nodeid, "wall": wall, "cpu": _usage(group), "group": str(group),
                               "started": dict(sorter.started)})  # fmt: skip

    def pytest_sessionfinish(self) -> None:
        """Writes each test's CPU at its end and now (`cpu_after`: with what its processes did since, and
        `kinds`: that split by the kind of process)."""
        self.out_dir.mkdir(parents=True, exist_ok=True)
        with open(self.out_dir / f"{self.worker}.jsonl", "a", encoding="utf-8") as out:
            for test in self.tests:
                group = Path(str(test.pop("group")))
                test["cpu_after"] = _usage(group)
                test["kinds"] = {kind.name: _usage(kind) for kind in group.iterdir() if kind.is_dir()}
                out.write(json.dumps(test) + "\n")
                for folder in [*group.iterdir(), group]:
                    with contextlib.suppress(OSError):  # only when no process of the test is left
                        folder.rmdir()
        with contextlib.suppress(OSError):
            self.root.rmdir()


def _usage(group: Path) -> float:
    return int((group / "cpuacct.usage").read_text()) / 1e9


def kind_of(cmdline: list[str]) -> str:
    """What a process the test started is, from its command line."""
    text = " ".join(cmdline)
    if "rostool.graph.daemon" in text:
        return "rostool daemon"
    if "-m rostool" in text or Path(cmdline[1:2][0] if cmdline[1:] else "").name == "rostool":
        return "rostool rclpy" if "--ros2-backend rclpy" in text else "rostool"
    if "ros2cli.daemon" in text:
        return "ros2 daemon"
    if cmdline[1:2] and cmdline[1].endswith("/ros2"):
        return "ros2"
    if "rclpy_peer.py" in text:
        return "rclpy peer"
    if text.startswith("/usr/bin/python3") or "rosmaster" in text or "roscore" in text:
        return "ROS 1 (Debian)"
    if "ray" in text:
        return "ray"
    script = " -c" if cmdline[1:2] == ["-c"] else ""
    return f"other {Path(cmdline[0]).name}{script}" if cmdline else "other"


class KindSorter:
    """Moves each process of the test, once it has exec'd, into a cgroup named by its kind (its children
    inherit that one until they exec something else: a daemon a verb starts is sorted on its own). What
    runs before a process is sorted (at most one poll, 50 ms) stays with its parent's kind."""

    def __init__(self, group: Path) -> None:
        self.group = group
        self.sorted: set[str] = set()
        self.started: dict[str, int] = defaultdict(int)  # processes sorted per kind
        self.me = str(os.getpid())  # the worker stays in `pytest`
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.done.wait(0.05):
            for kind in [d for d in self.group.iterdir() if d.is_dir()]:
                for pid in (kind / "cgroup.procs").read_text().split():
                    if pid != self.me:
                        self._sort(pid, kind.name)

    def _sort(self, pid: str, now: str) -> None:
        if pid in self.sorted:
            return  # a process is sorted once, when it first runs a program of its own
        try:
            raw = Path(f"/proc/{pid}/cmdline").read_bytes()
            ppid = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1]
            if raw == Path(f"/proc/{ppid}/cmdline").read_bytes():
                return  # forked, not exec'd (yet)
        except OSError:
            return  # gone already
        if not raw:
            return  # a zombie
        self.sorted.add(pid)
        kind = kind_of(raw.decode(errors="replace").rstrip("\0").split("\0"))
        self.started[kind] += 1
        if kind != now:
            with contextlib.suppress(OSError):
                (self.group / kind).mkdir(exist_ok=True)
                (self.group / kind / "cgroup.procs").write_text(pid)

    def stop(self) -> None:
        self.done.set()
        self.thread.join()


def register(config: pytest.Config) -> None:
    out = os.environ.get("ROSTOOL_TEST_CPU")
    if not out:
        return
    if not (CPUACCT / "cgroup.procs").exists() or os.geteuid() != 0:
        raise pytest.UsageError(f"ROSTOOL_TEST_CPU needs root and cgroup v1's cpuacct at {CPUACCT}")
    config.pluginmanager.register(CpuProfile(Path(out)), "rostool_cpu_profile")


def _records(out_dir: Path) -> list[dict[str, Any]]:
    return [
        json.loads(line) for path in sorted(out_dir.glob("*.jsonl")) for line in path.read_text().splitlines()
    ]


def summary(out_dir: Path, top: int = 0) -> str:
    """CPU and wall per module, the costliest first; then the `top` costliest tests."""
    modules: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0.0, 0])
    records = _records(out_dir)
    for test in records:
        row = modules[test["test"].split("::", 1)[0]]
        row[0] += test["cpu_after"]
        row[1] += test["cpu"]
        row[2] += test["wall"]
        row[3] += 1
    total = [sum(r[i] for r in modules.values()) for i in range(4)]
    lines = [f"{'module':55} {'tests':>5} {'CPU s':>8} {'in test':>8} {'wall s':>8} {'CPU/wall':>8}"]
    for module, (cpu_after, cpu, wall, count) in sorted(modules.items(), key=lambda kv: -kv[1][0]):
        ratio = cpu_after / wall if wall else 0.0
        lines.append(f"{module:55} {count:5d} {cpu_after:8.1f} {cpu:8.1f} {wall:8.1f} {ratio:8.2f}")
    lines.append(f"{'total':55} {int(total[3]):5d} {total[0]:8.1f} {total[1]:8.1f} {total[2]:8.1f}")
    kinds: dict[str, float] = defaultdict(float)
    started: dict[str, int] = defaultdict(int)
    for test in records:
        for kind, cpu in test.get("kinds", {}).items():
            kinds[kind] += cpu
        for kind, count in test.get("started", {}).items():
            started[kind] += count
    for kind, cpu in sorted(kinds.items(), key=lambda kv: -kv[1]):
        each = f"{started[kind]:6d} processes, {cpu / started[kind]:.3f} s each" if started[kind] else ""
        lines.append(f"  {kind:30} {cpu:8.1f} CPU s {each}")
    for test in sorted(records, key=lambda t: -t["cpu_after"])[:top]:
        lines.append(f"{test['cpu_after']:7.1f} CPU s {test['wall']:7.1f} wall s  {test['test']}")
    return "\n".join(lines)


if __name__ == "__main__":
    print(summary(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 0))
