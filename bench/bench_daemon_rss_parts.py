"""Which part of the DDS graph keeps memory per churned participant (issue 21, "daemon RSS flat"): the same
churn as soak_daemon.py (a Fast DDS participant with a node, a publisher, a subscription and a service
joins every second and one leaves), watched side by side by one process per VARIANT, each a DDS graph cache
(participant and built-in readers, polled every 0.25 s as the daemon's is) plus one part of the Session:

    .venv/bin/python bench/bench_daemon_rss_parts.py [--minutes 6] [--variants cache,writer,...]

- cache: the graph cache alone
- writer: + the ros_discovery_info writer (reliable, transient-local, keep-last 1), one announcement
- reader_all: + the ros_discovery_info reader as the Session made it (reliable, transient-local, keep-all)
- reader_last1: + the reader with keep-last 1 (what rmw's graph cache needs: one sample per writer)
- reader_last64: + the reader with keep-last 64
- both_all: + the writer and the keep-all reader, as the Session made them before issue 21's fixes
- session: a Session as it is now (with its readers made for newcomers whose nodes were missed)

Every SAMPLE seconds each process's RSS is read from /proc, and each process reports what malloc has handed
out and not had back (glibc's mallinfo2: in-use chunks of every arena plus mmapped blocks; Python's small
objects live in pymalloc's own arenas, which tracemalloc showed flat): RSS growing with that flat is the
allocator's fragmentation, growing with it is memory kept. Slopes: least-squares fits after WARMUP s. Each
process runs with MALLOC_ARENA_MAX=2, as the daemon does. Also counted: how many of the churned Fast DDS
participants each variant ever named, and how soon after it saw the participant.
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

from _graph import VENV_PYTHON, ros2_env
from bench_daemon_rss import slope_mib_per_min
from soak_daemon import churning, rss_kib

SAMPLE = 10.0
WARMUP = 120.0
VARIANTS = ("cache", "writer", "reader_all", "reader_last1", "both_all", "session")

WATCHER = r"""
import sys, time
from rostool.graph.ros2 import dds
from rostool.graph.ros2.discovery import (DISCOVERY_TOPIC, DISCOVERY_TYPE, GraphCache, NodeEntry,
                                          encode_entities_info)
from rostool.graph.ros2.session import Session
from rostool.graph.ros2.types import TypeSupport, gid_size
from rostool.graph.ros2_base.qos import QosProfile
from cyclonedds.core import Policy, Qos
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds._clayer import ddspy_write

variant = sys.argv[1]
types = TypeSupport("jazzy")
participant = dds.Participant()
cache = GraphCache(participant)
user_data = types.user_data(DISCOVERY_TYPE)
if variant == "session":
    session = Session("watch_session", types, cache)
elif variant != "cache":
    topic = Topic(participant.dp, DISCOVERY_TOPIC, types.idl_class(DISCOVERY_TYPE))
    if variant in ("writer", "both_all"):
        writer = DataWriter(participant.dp, topic,
                            qos=dds.to_dds_qos(QosProfile("reliable", "transient_local", 1), user_data))
        node = NodeEntry("/", f"watch_{variant}")
        ddspy_write(writer._ref, encode_entities_info(participant.guid, [node], gid_size("jazzy")))
    if variant != "writer":
        depth = {"reader_last1": 1, "reader_last64": 64}.get(variant, 0)
        qos = dds.to_dds_qos(QosProfile("reliable", "transient_local", depth), user_data)
        cache.info_reader = DataReader(participant.dp, topic, qos=Qos(*qos.policies,
                                                                      Policy.IgnoreLocal.Participant))
import ctypes
class MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in ("arena", "ordblks", "smblks", "hblks", "hblkhd",
                "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
libc = ctypes.CDLL(None)
libc.mallinfo2.restype = MallInfo2
print("ready", flush=True)
seen, named, last_report, began = {}, {}, time.monotonic(), time.monotonic()
while True:
    cache.poll()
    now = time.monotonic()
    for key in cache.participants:
        if key.startswith(b"\x01\x0f"):
            seen.setdefault(key, cache.first_seen.get(key, now))
    for key, nodes in cache.nodes.items():
        if key in seen and key not in named and nodes:
            named[key] = now - seen[key]
    if now - last_report >= 10:
        delays = sorted(named.values())
        median = delays[len(delays) // 2] if delays else float("nan")
        print(f"named {len(named)} {len(seen)} {median:.2f} {max(delays, default=float('nan')):.2f}",
              flush=True)
        info = libc.mallinfo2()  # bytes malloc has handed out and not had back (all arenas, and mmapped)
        print(f"heap {now - began:.1f} {(info.uordblks + info.hblkhd) // 1024}", flush=True)
        last_report = now
    time.sleep(0.25)
"""


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--minutes", type=float, default=6.0)
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--under", default="", help="a command to run each watcher under (e.g. heaptrack)")
    args = parser.parse_args()
    variants = [v for v in args.variants.split(",") if v]
    scratch = Path(tempfile.mkdtemp(prefix="rtp"))
    env = {**ros2_env(), "MALLOC_ARENA_MAX": "2"}
    print(f"load average at start: {os.getloadavg()[0]:.1f}", flush=True)
    watchers: dict[str, subprocess.Popen[str]] = {}
    rows: dict[str, list[tuple[float, int]]] = {v: [] for v in variants}
    try:
        for variant in variants:
            script = scratch / "watcher.py"  # a file, not -c: wrappers such as heaptrack re-quote arguments
            script.write_text(WATCHER)
            watchers[variant] = subprocess.Popen([*args.under.split(), VENV_PYTHON, str(script), variant],
                                                 env=env, stdout=subprocess.PIPE, text=True)  # fmt: skip
        for variant, proc in watchers.items():
            assert proc.stdout is not None
            while (line := proc.stdout.readline()) and line.strip() != "ready":
                pass  # a wrapper's own lines
            if not line:
                sys.exit(f"{variant} did not start")
        with churning(env, scratch):
            start = time.monotonic()
            print("| s | " + " | ".join(variants) + " |", flush=True)
            while time.monotonic() - start < args.minutes * 60:
                time.sleep(SAMPLE)
                now = time.monotonic() - start
                for variant, proc in watchers.items():
                    rows[variant].append((now, rss_kib(proc.pid)))
                if len(rows[variants[0]]) % 3 == 0:
                    cells = " | ".join(f"{rows[v][-1][1] / 1024:.2f}" for v in variants)
                    print(f"| {now:.0f} | {cells} | load {os.getloadavg()[0]:.1f}", flush=True)
        for proc in watchers.values():
            proc.terminate()
        print(f"\n| variant | RSS at {WARMUP:.0f} s | last | slope after {WARMUP:.0f} s (MiB/min) | malloc "
              f"in use: at {WARMUP:.0f} s, last, slope | Fast DDS participants named / seen | seen -> named, "
              "median, max (s) |")  # fmt: skip
        print("|---|---|---|---|---|---|---|")
        for variant, proc in watchers.items():
            series = rows[variant]
            at = min(series, key=lambda row: abs(row[0] - WARMUP))
            out, _ = proc.communicate(timeout=10)
            report = [line.split() for line in out.splitlines() if line.startswith("named ")]
            _, named, seen, median, worst = report[-1] if report else ("", "?", "?", "?", "?")
            heap = [(float(t), int(kib)) for _, t, kib in
                    (line.split() for line in out.splitlines() if line.startswith("heap "))]  # fmt: skip
            heap_at = min(heap, key=lambda row: abs(row[0] - WARMUP)) if heap else (0.0, 0)
            heap_last = heap[-1] if heap else (0.0, 0)
            print(f"| {variant} | {at[1] / 1024:.2f} MiB | {series[-1][1] / 1024:.2f} MiB at "
                  f"{series[-1][0]:.0f} s | {slope_mib_per_min(series):+.3f} | {heap_at[1] / 1024:.2f}, "
                  f"{heap_last[1] / 1024:.2f} MiB, {slope_mib_per_min(heap):+.3f} | {named} / {seen} | "
                  f"{median}, {worst} |")  # fmt: skip
    finally:
        for proc in watchers.values():
            proc.terminate()
            proc.wait(timeout=10)
        shutil.rmtree(scratch, ignore_errors=True)
        print(f"load average at end: {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
