"""Whole `rostool bag export` of one large .mcap of a fixed-layout type against the readers it is measured by.

Generates N sensor_msgs/msg/Imu messages (~330 bytes each) into a rosbag2 directory with one .mcap (rosbags'
writer; a few thousand distinct messages repeated with new timestamps), then times, each as a new process:
- `rostool bag export BAG -o OUT` (Parquet), and the same with an older rostool checkout when
  `--baseline PATH` names one (its PYTHONPATH), to show the change;
- the mcap library iterating every message without decoding (`make_reader(...).iter_messages()`);
- rosbags' AnyReader reading and deserializing every message.
Each figure is the median of `--runs` runs (wall and CPU seconds of the child, from os.wait4).

Run: .venv/bin/python bench/bench_export_columnar.py [--messages 1000000] [--runs 3] [--baseline /path/to/old]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_columnar import messages

MCAP_ITER = """
import sys
from mcap.reader import make_reader
n = 0
for path in sys.argv[1:]:
    with open(path, "rb") as f:
        for _schema, _channel, _message in make_reader(f).iter_messages():
            n += 1
print(n)
"""
ROSBAGS_READ = """
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
n = 0
with AnyReader([Path(sys.argv[1])]) as reader:
    for conn, _t, raw in reader.messages():
        reader.deserialize(raw, conn.msgtype)
        n += 1
print(n)
"""


def generate(path: Path, count: int) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    datas = messages(store, "sensor_msgs/msg/Imu", 4000)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for i in range(count):
            writer.write(conn, 1_000_000_000 + i * 1000, datas[i % len(datas)])


def timed(
    command: list[str], env: dict[str, str], runs: int, before: Path | None, cwd: Path
) -> tuple[float, float]:
    """Median wall and CPU seconds of `command` as a new process (run in `cwd`: `python -m` puts the current
    directory first on its path, which would hide a baseline given by PYTHONPATH)."""
    walls, cpus = [], []
    for _ in range(runs):
        if before is not None:
            shutil.rmtree(before, ignore_errors=True)
        start = time.perf_counter()
        proc = subprocess.Popen(command, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _pid, status, usage = os.wait4(proc.pid, 0)
        walls.append(time.perf_counter() - start)
        cpus.append(usage.ru_utime + usage.ru_stime)
        if status:
            raise SystemExit(f"{command} failed: {proc.stderr.read().decode() if proc.stderr else ''}")
    return statistics.median(walls), statistics.median(cpus)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--messages", type=int, default=1_000_000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--baseline", type=Path, help="an older rostool checkout to compare with")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-export-") as tmp:
        bag, out = Path(tmp) / "imu", Path(tmp) / "out"
        generate(bag, args.messages)
        mcap_file = next(bag.glob("*.mcap"))
        size = mcap_file.stat().st_size
        env = dict(os.environ)
        export = [sys.executable, "-m", "rostool", "bag", "export", str(bag), "-o", str(out)]
        rows = [
            ("rostool bag export (Parquet)", export, env, out),
            (
                "mcap library, iterate without decoding",
                [sys.executable, "-c", MCAP_ITER, str(mcap_file)],
                env,
                None,
            ),
            (
                "rosbags AnyReader, read + deserialize",
                [sys.executable, "-c", ROSBAGS_READ, str(bag)],
                env,
                None,
            ),
        ]
        if args.baseline:
            old = {**env, "PYTHONPATH": str(args.baseline)}
            rows.insert(1, (f"rostool bag export, {args.baseline.name}", export, old, out))
        load = os.getloadavg()[0]
        print(f"{args.messages:,} Imu messages, {size / 1e6:.0f} MB .mcap; load average {load:.1f}")
        print("| what | wall s | CPU s | msg/s (CPU) |")
        print("|---|---|---|---|")
        for label, command, run_env, before in rows:
            wall, cpu = timed(command, run_env, args.runs, before, cwd=Path(tmp))
            print(f"| {label} | {wall:.2f} | {cpu:.2f} | {args.messages / cpu:,.0f} |")


if __name__ == "__main__":
    main()
