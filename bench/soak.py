"""Soak: `bag record`, `topic echo` (into a pipe) and `topic hz` on one fast topic at once, for a minute.

    .venv/bin/python bench/soak.py [--seconds 60] [--rate 20000] [--ros2-rate 5000] [--ros2-echo-depth N]
        [--publishers 4] [--only ros1|ros2]

ROS 1: Debian's rosmaster on a free 127.0.0.1 port and --publishers rospy publishers (Debian's python3,
queue_size 100000 per subscriber) sending numbered std_msgs/Int32 at --rate in all (at most; as fast as
they can when slower) for --seconds once the three rostool processes subscribed.
ROS 2: a real rclpy talker (tests/rclpy_peer.py, Jazzy, Fast DDS on loopback,
reliable, depth 1000) sending exactly rate x seconds std_msgs/String "hello N" at --ros2-rate once the
three matched, on a domain of its own. Every second the resident memory (psutil if installed, else
/proc/PID/status VmRSS) of each rostool process is sampled; reported: start (after 3 s), peak and end,
and the counts each consumer saw against what the publisher sent (the bag is read back with rosbags;
echo's pipe is counted line by line; hz's last `average rate`).
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from _graph import ROOT, debian_env, free_port, loopback_env, ros2_env, start_master

PUBLISHER = """
import sys, time
import rospy
from std_msgs.msg import Int32
rate, seconds, subs, base = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
rospy.init_node('soak_pub', anonymous=True)
pub = rospy.Publisher('/soak', Int32, queue_size=100000)
while pub.get_num_connections() < subs:
    time.sleep(0.01)
time.sleep(1.0)
print('start', flush=True)
start = time.time()
sent = 0
while time.time() - start < seconds:  # at most RATE; slower when the publisher cannot keep up
    due = start + sent / rate
    now = time.time()
    if now < due:
        time.sleep(min(due - now, 0.001))
        continue
    burst = min(int((now - start) * rate) + 1, sent + 200)
    while sent < burst:
        pub.publish(Int32(data=base + sent))
        sent += 1
print('%d %.6f' % (sent, time.time() - start), flush=True)
time.sleep(3.0)
"""


def rss_kib(pid: int) -> int:
    try:
        import psutil  # type: ignore[import-untyped]

        return int(psutil.Process(pid).memory_info().rss // 1024)
    except ImportError:
        pass
    except Exception:  # the process is gone
        return 0
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


@dataclass
class Consumer:
    name: str
    proc: subprocess.Popen[str]
    samples: list[int] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    counted: int = 0


def start_consumers(env: dict[str, str], work: Path, topic: str, echo: Sequence[str] = ()) -> list[Consumer]:
    rostool = [sys.executable, "-m", "rostool"]
    bag = work / "soak.bag" if env.get("ROS_VERSION") != "2" else work / "soak.mcap"
    commands = {
        "bag record": [*rostool, "bag", "record", "-q", topic, "-O", str(bag)],
        "topic echo": [*rostool, "topic", "echo", topic, *echo],
        "topic hz": [*rostool, "topic", "hz", topic],
    }
    consumers = []
    for name, command in commands.items():
        proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=_interruptible)  # fmt: skip
        consumers.append(Consumer(name, proc))
    for consumer in consumers:
        threading.Thread(target=_read, args=(consumer,), daemon=True).start()
    return consumers


def _interruptible() -> None:
    """SIGINT as in a terminal, also when this script runs in the background (`cmd &` ignores it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _read(consumer: Consumer) -> None:
    assert consumer.proc.stdout is not None
    echo = consumer.name == "topic echo"
    for line in consumer.proc.stdout:
        if echo:
            if line.startswith("data:"):
                consumer.counted += 1
        else:
            consumer.lines.append(line)


def sample_until(consumers: list[Consumer], done: threading.Event) -> None:
    while not done.wait(1.0):
        for consumer in consumers:
            consumer.samples.append(rss_kib(consumer.proc.pid))


def finish(consumers: list[Consumer]) -> dict[str, str]:
    errors = {}
    for consumer in consumers:
        consumer.proc.send_signal(signal.SIGINT)
    for consumer in consumers:
        try:
            _out, err = consumer.proc.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            consumer.proc.kill()
            _out, err = consumer.proc.communicate()
        errors[consumer.name] = err.strip()
    return errors


def bag_count(path: Path) -> int:
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return sum(1 for _ in reader.messages())


def last_rate(lines: list[str]) -> str:
    rates = [m[1] for line in lines if (m := re.search(r"average rate: ([\d.]+)", line))]
    return rates[-1] if rates else "-"


def report(title: str, consumers: list[Consumer], sent: int, seconds: float, counts: dict[str, Any]) -> None:
    print(f"\n{title}: sent {sent:,} in {seconds:.1f} s ({sent / max(seconds, 1e-9):,.0f} msg/s)")
    print("| process | RSS start (MiB) | peak | end | end - start | received | lost |")
    print("|---|---|---|---|---|---|---|")
    for consumer in consumers:
        samples = consumer.samples[3:] or consumer.samples
        start, peak, end = samples[0] / 1024, max(samples) / 1024, samples[-1] / 1024
        got = counts[consumer.name]
        lost = sent - got if isinstance(got, int) else "-"
        row = [consumer.name, f"{start:.1f}", f"{peak:.1f}", f"{end:.1f}", f"{end - start:+.1f}", got, lost]
        print("| " + " | ".join(map(str, row)) + " |")


def soak_ros1(seconds: float, rate: float, publishers: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = loopback_env(free_port())
        env["ROS_HOME"] = str(work)
        master = start_master(env)
        consumers: list[Consumer] = []
        try:
            consumers = start_consumers(env, work, "/soak")
            script = work / "soak_pub.py"
            script.write_text(PUBLISHER)
            share = str(rate / publishers)
            pubs = [
                subprocess.Popen(
                    ["/usr/bin/python3", str(script), share, str(seconds), "3", str(k * 10**8)],
                    env=debian_env(env),
                    stdout=subprocess.PIPE,
                    text=True,
                )
                for k in range(publishers)
            ]
            for publisher in pubs:
                assert publisher.stdout is not None
                if publisher.stdout.readline().strip() != "start":
                    raise SystemExit("a rospy publisher did not start")
            done = threading.Event()
            sampler = threading.Thread(target=sample_until, args=(consumers, done), daemon=True)
            sampler.start()
            sent, took = 0, 0.0
            for publisher in pubs:
                assert publisher.stdout is not None
                sent_text = publisher.stdout.readline().split()
                sent, took = sent + int(sent_text[0]), max(took, float(sent_text[1]))
            time.sleep(3.0)  # let the consumers drain
            done.set()
            sampler.join()
            errors = finish(consumers)
            for publisher in pubs:
                publisher.wait(30)
            hz = next(c for c in consumers if c.name == "topic hz")
            counts = {
                "bag record": bag_count(work / "soak.bag"),
                "topic echo": next(c for c in consumers if c.name == "topic echo").counted,
                "topic hz": f"last average rate {last_rate(hz.lines)}",
            }
            report(f"ROS 1 (target {rate:,.0f} msg/s)", consumers, sent, took, counts)
            _errors(errors)
        finally:
            for consumer in consumers:
                if consumer.proc.poll() is None:
                    consumer.proc.kill()
            master.terminate()
            master.wait(10)


def soak_ros2(seconds: float, rate: float, echo_depth: int | None) -> None:
    from tests.ros2_peers import RclpyPeer

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = ros2_env()
        echo = ["--qos-depth", str(echo_depth)] if echo_depth is not None else []
        consumers = start_consumers(env, work, "/soak", echo)
        total = int(rate * seconds)
        args = [
            "--talk",
            "/soak",
            "--count",
            str(total),
            "--rate",
            str(rate),
            "--subs",
            "3",
            "--depth",
            "1000",
        ]
        peer = RclpyPeer("jazzy", env, work, args)
        try:
            peer.wait_for("ready", timeout=60)
            done = threading.Event()
            sampler = threading.Thread(target=sample_until, args=(consumers, done), daemon=True)
            sampler.start()
            sent_event = peer.wait_for("sent", timeout=seconds * 3 + 120)
            time.sleep(3.0)
            done.set()
            sampler.join()
            errors = finish(consumers)
            hz = next(c for c in consumers if c.name == "topic hz")
            counts = {
                "bag record": bag_count(work / "soak.mcap"),
                "topic echo": next(c for c in consumers if c.name == "topic echo").counted,
                "topic hz": f"last average rate {last_rate(hz.lines)}",
            }
            qos = " ".join(echo) or "default QoS"
            title = f"ROS 2 (Jazzy rclpy talker, target {rate:,.0f} msg/s, echo {qos})"
            report(title, consumers,
                   int(sent_event["count"]), float(sent_event["seconds"]), counts)  # fmt: skip
            _errors(errors)
        finally:
            peer.stop()
            for consumer in consumers:
                if consumer.proc.poll() is None:
                    consumer.proc.kill()


def _errors(errors: dict[str, str]) -> None:
    for name, text in errors.items():
        if text:
            print(f"{name} stderr: {text[-300:]!r}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rate", type=float, default=20000.0, help="ROS 1 messages per second")
    parser.add_argument("--ros2-rate", type=float, default=5000.0, help="ROS 2 messages per second")
    parser.add_argument("--publishers", type=int, default=4, help="rospy publishers sharing --rate")
    parser.add_argument("--ros2-echo-depth", type=int, help="ROS 2: `topic echo --qos-depth N` (0: keep all)")
    parser.add_argument("--only", choices=["ros1", "ros2"])
    args = parser.parse_args()
    os.chdir(ROOT)
    if args.only in (None, "ros1"):
        soak_ros1(args.seconds, args.rate, args.publishers)
    if args.only in (None, "ros2"):
        soak_ros2(args.seconds, args.ros2_rate, args.ros2_echo_depth)


if __name__ == "__main__":
    main()
