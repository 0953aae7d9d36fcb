"""What ending a verb with `os._exit` (rostool/_entry.py) saves against the interpreter's finalization:
the same commands run alternately through the console entry (`python -m rostool`: flush, atexit, os._exit)
and through `rostool.cli.main()` called directly (a normal interpreter exit), RUNS times each.

    .venv/bin/python bench/bench_exit.py [--runs 15]

Commands: `bag info` of a small .mcap (rosbags loaded), a direct DDS `topic list --spin-time 0.3` on an
empty domain (cyclonedds loaded, a participant made and closed), and `topic list` through a warm graph
daemon on that domain. Wall time per process, medians.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from _graph import VENV_PYTHON, ros2_env

ENTRY = [VENV_PYTHON, "-m", "rostool"]
FINALIZED = [VENV_PYTHON, "-c", "import sys; sys.argv[0] = 'rostool'; from rostool.cli import main; main()"]


def write_bag(path: Path) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    string = store.types["std_msgs/msg/String"]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        for n in range(100):
            writer.write(conn, n * 10_000_000, store.serialize_cdr(string(data=f"n {n}"), conn.msgtype))


def timed(command: list[str], env: dict[str, str]) -> tuple[float, int]:
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, timeout=60)
    return time.perf_counter() - start, done.returncode


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=15)
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="rte"))
    bag = scratch / "strings"
    write_bag(bag)
    (scratch / "run").mkdir(mode=0o700)
    direct = ros2_env()
    served = {**direct, "ROSTOOL_NO_DAEMON": "", "XDG_RUNTIME_DIR": str(scratch / "run"),
              "XDG_STATE_HOME": str(scratch / "state"), "ROSTOOL_DAEMON_BUILD": "exit"}  # fmt: skip
    cases = {
        "bag info (.mcap)": (["bag", "info", str(bag)], direct),
        "topic list --spin-time 0.3, direct DDS, empty domain": (
            ["--ros2", "--ros2-backend", "dds", "topic", "list", "--spin-time", "0.3"], direct),
        "topic list, warm daemon, empty domain": (
            ["--ros2", "--ros2-backend", "dds", "topic", "list"], served),
    }  # fmt: skip
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    try:
        subprocess.run([*ENTRY, "--ros2", "--ros2-backend", "dds", "daemon", "start"], env=served,
                       capture_output=True, timeout=60, check=True)  # fmt: skip
        print("| command | os._exit (entry): median, exit code | finalized: median, exit code | saved |")
        print("|---|---|---|---|")
        for label, (verb, env) in cases.items():
            fast: list[float] = []
            slow: list[float] = []
            codes = set()
            for _ in range(args.runs):
                for command, into in ((ENTRY, fast), (FINALIZED, slow)):
                    seconds, code = timed([*command, *verb], env)
                    into.append(seconds)
                    codes.add((command is ENTRY, code))
            fast_code = sorted(c for entry, c in codes if entry)
            slow_code = sorted(c for entry, c in codes if not entry)
            quick, slower = statistics.median(fast), statistics.median(slow)
            print(f"| {label} | {quick:.3f} s, {fast_code} | {slower:.3f} s, {slow_code} | "
                  f"{slower - quick:.3f} s |", flush=True)  # fmt: skip
    finally:
        subprocess.run([*ENTRY, "--ros2", "--ros2-backend", "dds", "daemon", "stop"], env=served,
                       capture_output=True, timeout=60)  # fmt: skip
        shutil.rmtree(scratch, ignore_errors=True)
        print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
