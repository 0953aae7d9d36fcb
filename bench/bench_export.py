"""Benchmark `rostool bag export` (Parquet, CSV) against rosbags' reader alone, and `-j 2` on 20 bags.

Generates (in a temporary directory under /tmp, removed afterwards):
- odom.bag: nav_msgs/Odometry messages (header, nested pose/twist, two 36-float covariance arrays;
  ~700 bytes each), the typical small-message table;
- camera.bag: sensor_msgs/Image 640x480 rgb8 (921,600 bytes of pixels each) plus a 100 Hz Twist topic,
  as bench_bag_info.py makes them: large messages, where the bytes dominate;
- fleet/: 20 smaller Odometry bags, for `rostool bag export fleet/ -j 1` vs `-j 2`.
Each command runs as a user runs it (a new process, warm page cache, best of N runs); peak memory is the
command's maximum resident set size. The floor is rosbags' AnyReader reading and deserializing every
message, in this process.

Run: .venv/bin/python bench/bench_export.py [--odom-msgs 400000] [--camera-gb 0.5] [--fleet-msgs 20000]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_bag_info import generate_bag


def generate_odom(path: Path, count: int) -> int:
    import numpy as np
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    types = store.types
    vec = types["geometry_msgs/msg/Vector3"]
    covariance = np.arange(36, dtype=np.float64)
    with Writer(path) as writer:
        conn = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=store)
        start = 1_700_000_000_000_000_000
        for i in range(count):
            stamp = start + i * 10_000_000
            time_msg = types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
            header = types["std_msgs/msg/Header"](seq=i, stamp=time_msg, frame_id="odom")
            pose = types["geometry_msgs/msg/Pose"](
                types["geometry_msgs/msg/Point"](i * 0.01, 2.0, 0.0),
                types["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
            )
            msg = types["nav_msgs/msg/Odometry"](
                header,
                "base_link",
                types["geometry_msgs/msg/PoseWithCovariance"](pose, covariance),
                types["geometry_msgs/msg/TwistWithCovariance"](
                    types["geometry_msgs/msg/Twist"](vec(1.0, 0.0, 0.0), vec(0.0, 0.0, 0.1)), covariance
                ),
            )
            writer.write(conn, stamp, store.serialize_ros1(msg, "nav_msgs/msg/Odometry"))
    return count


def rosbags_floor(path: Path) -> tuple[float, int]:
    """Seconds for rosbags' AnyReader to read and deserialize every message (no output)."""
    from rosbags.highlevel import AnyReader

    start = time.perf_counter()
    count = 0
    with AnyReader([path]) as reader:
        for conn, _t, data in reader.messages():
            reader.deserialize(data, conn.msgtype)
            count += 1
    return time.perf_counter() - start, count


RSS = "import resource,subprocess,sys; subprocess.run(sys.argv[1:],check=True,capture_output=True); " \
      "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"  # fmt: skip


def timed(cmd: list[str], runs: int) -> tuple[float, int]:
    """Best wall time over `runs` and the peak RSS (KB) of the command."""
    best, peak = float("inf"), 0
    for _ in range(runs):
        start = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", RSS, *cmd], check=True, capture_output=True, text=True)
        best = min(best, time.perf_counter() - start)
        peak = max(peak, int(out.stdout.strip()))
    return best, peak


def export_cmd(src: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "rostool", "bag", "export", str(src), "-o", str(out), *extra]


def row(label: str, seconds: float, count: int, size: int, rss_kb: int | None = None) -> None:
    memory = f", peak RSS {rss_kb / 1024:.0f} MB" if rss_kb else ""
    rate = f"{count / seconds:9.0f} msgs/s  {size / seconds / 1e6:7.1f} MB/s"
    print(f"{label:<40} {seconds:7.2f} s  {rate}{memory}")


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--odom-msgs", type=int, default=400_000)
    parser.add_argument("--camera-gb", type=float, default=0.5)
    parser.add_argument("--fleet-msgs", type=int, default=20_000, help="Odometry messages per fleet bag")
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--fleet-only", action="store_true", help="Only the -j 1 / -j 2 comparison")
    args = parser.parse_args()
    print(f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    work = Path(tempfile.mkdtemp(prefix="rostool-bench-export-", dir="/tmp"))
    try:
        odom, camera, fleet = work / "odom.bag", work / "camera.bag", work / "fleet"
        singles = [] if args.fleet_only else [odom, camera]
        if singles:
            count = generate_odom(odom, args.odom_msgs)
            print(f"generated {odom.name}: {odom.stat().st_size / 1e6:.0f} MB, {count} msgs")
            count = generate_bag(camera, args.camera_gb)
            print(f"generated {camera.name}: {camera.stat().st_size / 1e6:.0f} MB, {count} msgs")
        fleet.mkdir()
        for i in range(20):
            generate_odom(fleet / f"robot{i:02d}.bag", args.fleet_msgs)
        fleet_size = sum(p.stat().st_size for p in fleet.iterdir())
        print(f"generated {fleet.name}/: 20 bags, {fleet_size / 1e6:.0f} MB, {20 * args.fleet_msgs} msgs")
        for bag in singles:
            size = bag.stat().st_size
            floor, count = rosbags_floor(bag)
            print(f"\n{bag.name}: {count} msgs, {size / 1e6:.0f} MB")
            row("rosbags AnyReader, read + deserialize", floor, count, size)
            for fmt in ("parquet", "csv"):
                if fmt == "csv" and bag == camera:
                    continue  # image bytes as JSON text: not what anyone exports to CSV
                out = work / f"out-{bag.stem}-{fmt}"
                seconds, rss = timed(export_cmd(bag, out, "--format", fmt), args.runs)
                written = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
                row(f"rostool bag export --format {fmt}", seconds, count, size, rss)
                print(f"{'':40} {seconds / floor:7.2f}x rosbags' time; output {written / 1e6:.0f} MB")
                shutil.rmtree(out)
        total = 20 * args.fleet_msgs
        print(f"\nfleet/: 20 bags, {total} msgs, {fleet_size / 1e6:.0f} MB")
        results = {}
        for jobs in ("1", "2"):
            out = work / f"out-fleet-{jobs}"
            seconds, rss = timed(export_cmd(fleet, out, "-j", jobs), args.runs)
            results[jobs] = seconds
            row(f"rostool bag export fleet/ -j {jobs}", seconds, total, fleet_size, rss)
            shutil.rmtree(out)
        print(f"speed-up of -j 2: {results['1'] / results['2']:.2f}x")
        print(f"load average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
