"""ROS 2 over DDS: `topic hz` accuracy, `topic echo` throughput, start-up to the first discovered topic.

    .venv/bin/python bench/bench_ros2.py [hz|echo|startup|record]...

Loopback only (rostool's LOCALHOST discovery: 127.0.0.1, multicast off), a fresh ROS_DOMAIN_ID per run.
No ROS 2 installation here, so there is no side-by-side ros2cli column: numbers are absolute.
"""

from __future__ import annotations

import json
import signal
import statistics
import subprocess
import sys
import threading
import time
from typing import IO

from _graph import cpu_seconds, ros2_env, rostool_cmd

VENV_PYTHON = sys.executable

# Publishes exactly COUNT std_msgs/Int32 (counting up) at RATE (0: as fast as possible) once SUBS readers
# matched, with rostool's ROS 2 publisher (default QoS: reliable, volatile, keep last 10), then prints
# "sent N in S seconds".
PUBLISHER = r"""
import struct, sys, time
from rostool.graph.ros2.graph import Ros2Graph
count, rate, subs = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
graph = Ros2Graph("bench_pub")
pub = graph.publisher("/bench", "std_msgs/msg/Int32")
if not pub.wait_for_subscribers(subs, 30):
    sys.exit("subscribers did not match")
time.sleep(1.0)
period = 1.0 / rate if rate else 0.0
header = b"\x00\x01\x00\x00"
start = time.perf_counter()
for i in range(count):
    if period:
        delay = start + i * period - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    pub.publish_raw(header + struct.pack("<i", i))
elapsed = time.perf_counter() - start
print(f"sent {count} in {elapsed:.6f} seconds", flush=True)
try:
    time.sleep(3.0)
except KeyboardInterrupt:
    pass
graph.close()
"""


def start_publisher(env: dict[str, str], count: int, rate: float, subs: int) -> subprocess.Popen[str]:
    args = [VENV_PYTHON, "-c", PUBLISHER, str(count), str(rate), str(subs)]
    return subprocess.Popen(args, env=env, stdout=subprocess.PIPE, text=True)


def bench_hz(count: int, rate: float) -> None:
    env = ros2_env()
    pub = start_publisher(env, count, rate, 1)
    ours = subprocess.Popen(rostool_cmd("topic", "hz", "/bench", "--json"), env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)  # fmt: skip
    assert pub.stdout is not None
    sent_line = pub.stdout.readline()
    pub.wait()
    seconds = float(sent_line.split()[3])
    true_rate = (count - 1) / seconds
    time.sleep(2.5)
    cpu = cpu_seconds(ours.pid)
    ours.send_signal(signal.SIGINT)
    out = ours.communicate()[0]
    last = [json.loads(line) for line in out.splitlines() if line.startswith("{")][-1]
    label = f"{rate:g} msg/s" if rate else "max"
    print(f"hz {label:>11}: sent {count} at {true_rate:,.0f} msg/s")
    missed = 100 * (count - last["received"]) / count
    print(f"  rostool counted {last['received']:>7} ({missed:6.2f}% missed)  "
          f"rate {last['rate']:>10,.1f} ({100 * abs(last['rate'] - true_rate) / true_rate:6.2f}% error)  "
          f"cpu {cpu:5.2f}s")  # fmt: skip


def bench_echo(count: int, rate: float) -> None:
    env = ros2_env()
    pub = start_publisher(env, count, rate, 1)
    proc = subprocess.Popen(rostool_cmd("topic", "echo", "/bench"), env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)  # fmt: skip
    assert proc.stdout is not None and pub.stdout is not None
    stamps: list[float] = []

    def read(stream: IO[bytes]) -> None:
        for line in stream:
            if line == b"---\n":
                stamps.append(time.perf_counter())

    reader = threading.Thread(target=read, args=(proc.stdout,), daemon=True)
    reader.start()
    sent = pub.stdout.readline()  # after the last message went out
    deadline = time.monotonic() + 5.0
    while len(stamps) < count and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    proc.communicate()
    pub.send_signal(signal.SIGINT)
    pub.communicate()
    seen = len(stamps)
    label = f"{rate:g} msg/s" if rate else "max"
    rate_seen = (seen - 1) / (stamps[-1] - stamps[0]) if seen > 1 and stamps[-1] > stamps[0] else 0.0
    print(f"echo {label:>9}: {sent.strip()}; printed {seen} ({100 * (count - seen) / count:.2f}% missed), "
          f"{rate_seen:,.0f} msg/s")  # fmt: skip


def bench_startup() -> None:
    env = ros2_env()
    pub = start_publisher(env, 10**9, 10.0, 10**6)  # never starts sending; its topic is what we look for
    time.sleep(1.0)
    commands = {"topic list": ("topic", "list"), "topic type": ("topic", "type", "/bench")}
    results: dict[str, list[float]] = {label: [] for label in commands}
    for _ in range(7):
        for label, cmd in commands.items():
            start = time.perf_counter()
            done = subprocess.run(rostool_cmd(*cmd), env=env, capture_output=True, text=True, check=False)
            results[label].append(time.perf_counter() - start)
            assert "/bench" in done.stdout or "Int32" in done.stdout, done.stderr
    pub.send_signal(signal.SIGINT)
    pub.communicate()
    for label, times in results.items():
        print(f"startup {label}: median {statistics.median(times):.3f} s (min {min(times):.3f} s)")


def bench_record(count: int, rate: float) -> None:
    """`bag record` of COUNT messages into .mcap: how many the file holds, and the recorder's CPU."""
    import tempfile
    from pathlib import Path

    from rostool.bag.reader import BagReader

    env = ros2_env()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.mcap"
        pub = start_publisher(env, count, rate, 1)
        recorder = subprocess.Popen(rostool_cmd("bag", "record", "/bench", "-q", "-O", str(out)), env=env,
                                    stderr=subprocess.PIPE, text=True)  # fmt: skip
        assert pub.stdout is not None
        sent = pub.stdout.readline().strip()
        time.sleep(1.0)
        cpu = cpu_seconds(recorder.pid)
        recorder.send_signal(signal.SIGINT)
        _out, err = recorder.communicate()
        pub.send_signal(signal.SIGINT)
        pub.communicate()
        with BagReader([out]) as reader:
            values = [int.from_bytes(bytes(raw)[4:8], "little") for _c, _t, raw in reader.messages()]
    label = f"{rate:g} msg/s" if rate else "max"
    in_order = values == sorted(values)
    missed = 100 * (count - len(values)) / count
    print(f"record {label:>9}: {sent}; the bag holds {len(values)} ({missed:.2f}% missed, "
          f"in order: {in_order}), recorder cpu {cpu:.2f}s {err.strip()}")  # fmt: skip


def main() -> None:
    wanted = sys.argv[1:] or ["startup", "hz", "echo", "record"]
    if "startup" in wanted:
        bench_startup()
    if "hz" in wanted:
        bench_hz(10_000, 1_000)
        bench_hz(100_000, 10_000)
    if "echo" in wanted:
        bench_echo(10_000, 1_000)
        bench_echo(50_000, 10_000)
        bench_echo(20_000, 0)
    if "record" in wanted:
        bench_record(10_000, 1_000)
        bench_record(100_000, 10_000)
        bench_record(50_000, 0)


if __name__ == "__main__":
    main()
