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
        group.mkdir()
        (group / "cgroup.procs").write_text(str(os.getpid()))
        start = time.monotonic()
        try:
            yield
        finally:
            (self.home / "cgroup.procs").write_text(str(os.getpid()))
            wall = time.monotonic() - start
            cpu = int((group / "cpuacct.usage").read_text()) / 1e9
            self.tests.append({"test": item.nodeid, "wall": wall, "cpu": cpu, "group": str(group)})

    def pytest_sessionfinish(self) -> None:
        """Writes each test's CPU at its end and now (`cpu_after`: with what its processes did since)."""
        self.out_dir.mkdir(parents=True, exist_ok=True)
        with open(self.out_dir / f"{self.worker}.jsonl", "a", encoding="utf-8") as out:
            for test in self.tests:
                group = Path(str(test.pop("group")))
                test["cpu_after"] = int((group / "cpuacct.usage").read_text()) / 1e9
                out.write(json.dumps(test) + "\n")
                with contextlib.suppress(OSError):  # only when no process of the test is left
                    group.rmdir()
        with contextlib.suppress(OSError):
            self.root.rmdir()


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
    for test in sorted(records, key=lambda t: -t["cpu_after"])[:top]:
        lines.append(f"{test['cpu_after']:7.1f} CPU s {test['wall']:7.1f} wall s  {test['test']}")
    return "\n".join(lines)


if __name__ == "__main__":
    print(summary(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 0))
