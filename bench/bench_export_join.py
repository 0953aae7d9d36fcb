"""The join of a bag exported in pieces (bag/parquet_concat.py), with row groups as batches come (before) and
gathered into row groups of up to 1 Mi rows / 64 MiB (now).

One rosbag2 .mcap of N Imu (2,900,000 make ~1 GB) is exported in two pieces, one after the other in this
process, then the pieces are joined; "per batch" exports with `held_bytes=1` (every batch written as it comes:
a row group per chunk's batch, what export did before), "gathered" with the defaults. Medians of --runs.
The joined table is checked equal to a whole export's.

Run: .venv/bin/python bench/bench_export_join.py [--messages 2900000] [--runs 3] [--tmp /tmp/h1]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_export_ray import write_bag


def main() -> None:
    import pyarrow.parquet as pq

    from rostool.bag.export import ExportOptions, export_bag, join_pieces

    parser = argparse.ArgumentParser()
    parser.add_argument("--messages", type=int, default=2_900_000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--tmp", default=os.environ.get("BENCH_TMP"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-join-", dir=args.tmp) as tmp_name:
        tmp = Path(tmp_name)
        bag = write_bag(tmp / "imu", args.messages, 0)
        size = sum(f.stat().st_size for f in bag.iterdir()) / 2**20
        print(f"{args.messages:,} Imu, {size:,.0f} MiB; load average {os.getloadavg()[0]:.1f}")
        whole = tmp / "whole"
        export_bag(bag, ExportOptions(fmt="parquet", out=whole))
        reference = pq.read_table(whole / "imu.parquet")
        print("| row groups | groups per piece | export of the 2 pieces s | join s | joined MiB |")
        print("|---|---|---|---|---|")
        for label, settings in (("per batch (before)", {"held_bytes": 1}), ("gathered (now)", {})):
            exports, joins = [], []
            groups = 0
            for _ in range(args.runs):
                out = tmp / "out"
                shutil.rmtree(out, ignore_errors=True)
                options = ExportOptions(fmt="parquet", out=out, **settings)  # type: ignore[arg-type]
                start = time.perf_counter()
                pieces = [name for k in range(2) for name in export_bag(bag, options, piece=(k, 2)).pieces]
                exports.append(time.perf_counter() - start)
                groups = pq.ParquetFile(pieces[0]).num_row_groups
                start = time.perf_counter()
                join_pieces(pieces)
                joins.append(time.perf_counter() - start)
            joined = out / "imu.parquet"
            assert pq.read_table(joined).equals(reference)
            mib = joined.stat().st_size / 2**20
            cells = f"{statistics.median(exports):.2f} | {statistics.median(joins):.3f} | {mib:,.0f}"
            print(f"| {label} | {groups} | {cells} |")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
