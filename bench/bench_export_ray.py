"""`bag export` of several bags: `--engine ray` (a private local Ray) against the local engine, -j 1 and -j 2.

Two fleets, generated in /tmp and removed afterwards: BAGS rosbag2 .mcap bags of Imu messages (decoded
column-wise: cheap per message) and BAGS bags of tf2_msgs/TFMessage (sequences of messages: decoded one by
one, the expensive case). Each command is a new process; medians of --runs (wall and CPU of the child).

With --single N: one .mcap of N Imu messages (2,900,000 make ~1 GB) instead, cut into runs of chunks that
the workers export in parallel and that are joined byte-wise (bag/export_many.py); -j 1 exports it whole.

Run: .venv/bin/python bench/bench_export_ray.py [--bags 4] [--imu 1000000] [--tf 100000] [--runs 3]
     .venv/bin/python bench/bench_export_ray.py --single 2900000 [--runs 3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_columnar import messages
from bench_export_columnar import timed


def peak_rss_mib(command: list[str], env: dict[str, str], cwd: Path) -> float:
    """The largest resident set of the command's process tree (Linux: a waited-for child's maximum RSS
    includes its own waited-for children's, so local workers count; Ray's workers are Ray's, not ours)."""
    proc = subprocess.Popen(command, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return os.wait4(proc.pid, 0)[2].ru_maxrss / 1024


def fleet(root: Path, msgtype: str, bags: int, count: int) -> Path:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    datas = messages(store, msgtype, 2000)
    first = root / "bag0"
    with Writer(first, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/data", msgtype, typestore=store)
        for i in range(count):
            writer.write(conn, 1_000_000_000 + i * 1000, datas[i % len(datas)])
    for index in range(1, bags):
        shutil.copytree(first, root / f"bag{index}")
    return root


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--bags", type=int, default=4)
    parser.add_argument("--imu", type=int, default=1_000_000, help="Imu messages per bag")
    parser.add_argument("--tf", type=int, default=100_000, help="TFMessage messages per bag")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--single", type=int, default=0, help="one bag of this many Imu messages instead")
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_")}
    print(f"load average {os.getloadavg()[0]:.1f}, {os.cpu_count()} CPUs")
    print("| fleet | messages | engine | wall s | CPU s (driver) | vs -j 1 (wall) | peak RSS MiB |")
    print("|---|---|---|---|---|---|---|")
    cases = [("Imu", "sensor_msgs/msg/Imu", args.imu), ("TFMessage", "tf2_msgs/msg/TFMessage", args.tf)]
    if args.single:
        args.bags, cases = 1, [("Imu, one bag", "sensor_msgs/msg/Imu", args.single)]
    for label, msgtype, count in cases:
        with tempfile.TemporaryDirectory(prefix="bench-ray-", dir=os.environ.get("BENCH_TMP")) as tmp:
            root = fleet(Path(tmp) / "fleet", msgtype, args.bags, count)
            if args.single:
                root = root / "bag0"
                size = sum(f.stat().st_size for f in root.iterdir())
                print(f"one bag: {size / 2**20:.0f} MiB")
            out = Path(tmp) / "out"
            base = [sys.executable, "-m", "rostool", "bag", "export", str(root), "-o", str(out)]
            baseline = None
            for engine, extra in (
                ("local -j 1", ["-j", "1"]),
                ("local -j 2", ["-j", "2"]),
                ("ray", ["--engine", "ray"]),
            ):
                wall, cpu = timed(base + extra, env, args.runs, out, cwd=Path(tmp))
                baseline = baseline or wall
                shutil.rmtree(out, ignore_errors=True)
                rss = peak_rss_mib(base + extra, env, Path(tmp))
                row = f"| {label} x{args.bags} | {args.bags * count:,} | {engine} | {wall:.2f} | {cpu:.2f}"
                print(f"{row} | {baseline / wall:.2f}x | {rss:.0f} |")


if __name__ == "__main__":
    main()
