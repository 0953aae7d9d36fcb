"""Across machines: `topic hz` at 1 kHz and `topic echo` of a 0.92 MB image, rostool beside the real tool
(ros2cli Jazzy; Debian's rostopic), on a laptop, from a publisher on a robot. Both are private network
namespaces (tests/netns.py), so ROS's defaults (multicast, SUBNET discovery) run there and nothing touches
the host's own interfaces.

    .venv/bin/python bench/bench_across_machines.py [hz|echo]... [--ros 1|2|both] [--seconds S] [--json]

Needs root (ip netns). ROS 2: a real rclpy Jazzy node on the robot (the peer venv's python, publishing on
an absolute schedule: tests/rclpy_peer.py's timer holds only ~945 Hz of 1 kHz here); rostool on its DDS
backend without its graph daemon (ROSTOOL_NO_DAEMON=1, so its process does all the work); `ros2` with its
daemon started beforehand on the laptop, as a user's is. ROS 1: Debian's rosmaster and a rospy publisher on
the robot (ROS_IP: the robot), both tools with ROS_IP set to the laptop. The two tools of a pair start
together and run for the same window; CPU is each process's user+system time at the end of the window
(start-up included). echo: each image carries its number ("frame N" in header.frame_id), so the messages a
tool missed between the first and the last it printed are counted exactly.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from _graph import VENV_PYTHON, cpu_seconds

from tests.netns import Machine, PrivateNetwork, netns_missing, private_network
from tests.ros2_peers import PEERS_DIR, machine_peer_env
from tests.support import DEBIAN_PYTHON, debian_env, fresh_domain, wait_until

JAZZY = PEERS_DIR / "jazzy"
ROS2 = JAZZY / "bin" / "ros2"

# a robot's publisher (argv: 1|2, string|image, RATE): /fast std_msgs/String, or /image sensor_msgs/Image
# 640x480 rgb8 with its number N in header.frame_id ("frame N"), at RATE Hz on an absolute schedule, with
# rclpy (the Jazzy peer venv's python) or rospy (Debian's); prints {"count": N, "t": monotonic} every second
PUBLISHER = r"""
import array, json, sys, time
from sensor_msgs.msg import Image
from std_msgs.msg import String
ros, kind, rate = sys.argv[1], sys.argv[2], float(sys.argv[3])
cls, topic, data = (Image, "/image", bytes(640 * 480 * 3)) if kind == "image" else (String, "/fast", None)
if ros == "2":
    import rclpy
    rclpy.init()
    node = rclpy.create_node("robot_pub")
    pub, ok, stamp = node.create_publisher(cls, topic, 10), rclpy.ok, lambda: node.get_clock().now().to_msg()
    data = data and array.array("B", data)
else:
    import rospy
    rospy.init_node("robot_pub")
    pub = rospy.Publisher(topic, cls, queue_size=5 if data else 100)
    ok, stamp = lambda: not rospy.is_shutdown(), rospy.Time.now
msg = cls()
if data:
    msg.height, msg.width, msg.encoding, msg.step, msg.data = 480, 640, "rgb8", 640 * 3, data
print("ready", flush=True)
start = reported = time.monotonic()
count = 0
try:
    while ok():
        count += 1
        if data:
            msg.header.stamp = stamp()
            msg.header.frame_id = "frame %d" % count
        else:
            msg.data = "hello %d" % count
        pub.publish(msg)
        now = time.monotonic()
        if now - reported >= 1.0:
            reported = now
            print(json.dumps({"count": count, "t": now}), flush=True)
        delay = start + count / rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
except KeyboardInterrupt:
    pass
"""


class Run:
    """A process on a private machine whose stdout lines are kept as they come."""

    def __init__(self, machine: Machine, argv: list[str], env: dict[str, str]) -> None:
        self.proc = machine.popen(argv, env)
        self.lines: list[str] = []
        self.errors: list[str] = []
        self.reader = threading.Thread(target=self._read, args=(self.proc.stdout, self.lines), daemon=True)
        self.reader.start()
        threading.Thread(target=self._read, args=(self.proc.stderr, self.errors), daemon=True).start()

    @staticmethod
    def _read(stream: Any, into: list[str]) -> None:
        for line in stream:
            into.append(line.rstrip("\n"))

    def wait_for(self, text: str, timeout: float = 30) -> None:
        if not wait_until(lambda: text in self.lines or self.proc.poll() is not None, timeout):
            raise SystemExit(f"{self.proc.args[-3:]} did not print {text!r} within {timeout} s")
        if text not in self.lines:
            raise SystemExit(f"{self.proc.args[-3:]} ended (exit {self.proc.returncode}) before {text!r}")

    def reports(self) -> list[tuple[int, float]]:
        """A publisher's (count, monotonic time) reports."""
        reports = [json.loads(line) for line in self.lines if line.startswith("{")]
        return [(r["count"], r["t"]) for r in reports]

    def stop(self) -> float:
        """Its CPU seconds so far, then interrupt it (killed after 10 s) and wait for its output."""
        cpu = cpu_seconds(self.proc.pid) if self.proc.poll() is None else float("nan")
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.reader.join(timeout=10)
        return cpu


def true_rate(reports: list[tuple[int, float]], start: float, end: float) -> float:
    """The publisher's own rate over the reports that fell in [start, end]."""
    inside = [r for r in reports if start <= r[1] <= end] or reports
    (c0, t0), (c1, t1) = inside[0], inside[-1]
    return (c1 - c0) / (t1 - t0) if t1 > t0 else float("nan")


def silent(run: Run) -> None:
    """Say why a tool printed no result (its last lines)."""
    last = "\n  ".join((run.lines + run.errors)[-8:])
    print(f"{' '.join(run.proc.args[-4:])}: no result; its last lines:\n  {last}", file=sys.stderr)


def hz_result(run: Run, cpu: float, rate: float, _first: float) -> dict[str, Any]:
    rates = re.findall(r"average rate: ([\d.]+)", "\n".join(run.lines))
    if not rates:
        silent(run)
    seen = float(rates[-1]) if rates else float("nan")
    return {"rate": seen, "error_pct": 100 * abs(seen - rate) / rate, "cpu_s": cpu, "reports": len(rates)}


def echo_result(run: Run, cpu: float, rate: float, first: float) -> dict[str, Any]:
    """Messages printed; by their numbers, how many of the publisher's between the first and the last
    printed were missing; msgs/s = printed / (that span at the publisher's rate); seconds from the start
    to the publication of the first printed (`first`: the publisher's count at the start)."""
    text = "\n".join(run.lines)
    numbers = [int(n) for n in re.findall(r"frame (\d+)", text)]
    span = numbers[-1] - numbers[0] + 1 if numbers else 0
    got = len(set(numbers))
    if not numbers:
        silent(run)
    printed = sum(line.strip() == "---" for line in run.lines)
    per_s = got / (span / rate) if span > 1 else 0.0
    first_s = (numbers[0] - first) / rate if numbers else float("nan")
    return {"messages": printed, "numbered": got, "missing": span - got, "msgs_per_s": per_s,
            "first_s": first_s, "cpu_s": cpu}  # fmt: skip


def scenario(
    net: PrivateNetwork,
    kind: str,
    publisher: list[str],
    robot_env: dict[str, str],
    tools: dict[str, list[str]],
    envs: dict[str, dict[str, str]],
    seconds: float,
) -> dict[str, Any]:
    """PUBLISHER on the robot (`publisher`: interpreter, script, ROS version), then both tools on the
    laptop started together, each stopped after `seconds`; the publisher's true rate over that window and
    each tool's result."""
    hz = 1000 if kind == "hz" else 30
    pub = Run(net.robot, [*publisher, "string" if kind == "hz" else "image", str(hz)], robot_env)
    try:
        pub.wait_for("ready")
        wait_until(lambda: bool(pub.reports()), 10)  # its first count, to date the tools' first message
        began = time.monotonic()
        runs = {name: Run(net.laptop, argv, envs[name]) for name, argv in tools.items()}
        time.sleep(seconds)
        ended = time.monotonic()
        cpus = {name: run.stop() for name, run in runs.items()}
    finally:
        pub.stop()
    rate = true_rate(pub.reports(), began, ended)
    count, t = [r for r in pub.reports() if r[1] <= began][-1]
    first = count + (began - t) * rate  # the publisher's count when the tools started
    result = hz_result if kind == "hz" else echo_result
    return {"true_rate": rate, **{name: result(run, cpus[name], rate, first) for name, run in runs.items()}}


def bench_ros2(net: PrivateNetwork, what: list[str], seconds: float, tmp: Path) -> dict[str, Any]:
    base = {k: v for k, v in os.environ.items() if not k.startswith("ROS") and k != "CYCLONEDDS_URI"}
    base.update(PYTHONUNBUFFERED="1", ROSTOOL_NO_DAEMON="1", ROS_DOMAIN_ID=str(fresh_domain()))
    peer = machine_peer_env(base, tmp)
    real = dict(peer, AMENT_PREFIX_PATH=str(JAZZY), PATH=f"{JAZZY}/bin:{peer['PATH']}")
    envs = {"rostool": base, "real": real}
    net.laptop.run([str(ROS2), "daemon", "start"], envs["real"])
    publisher = [str(JAZZY / "bin" / "python"), "-c", PUBLISHER, "2"]
    results = {}
    try:
        for kind in what:
            args = [kind, "/fast"] if kind == "hz" else [kind, "/image", "--no-arr"]
            tools = {"rostool": [VENV_PYTHON, "-m", "rostool", "--ros2", "topic", *args],
                     "real": [str(ROS2), "topic", *args]}  # fmt: skip
            results[kind] = scenario(net, kind, publisher, peer, tools, envs, seconds)
    finally:
        net.laptop.run([str(ROS2), "daemon", "stop"], envs["real"])
    return results


def bench_ros1(net: PrivateNetwork, what: list[str], seconds: float, tmp: Path) -> dict[str, Any]:
    base = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    base.update(PYTHONUNBUFFERED="1", ROS_MASTER_URI=f"http://{net.robot.address}:11311",
                ROS_HOME=str(tmp), ROS_LOG_DIR=str(tmp))  # fmt: skip
    robot = debian_env({**base, "ROS_IP": net.robot.address})
    laptop = {**base, "ROS_IP": net.laptop.address}
    envs = {"rostool": laptop, "real": debian_env(laptop)}
    master = Run(net.robot, ["rosmaster", "--core", "-p", "11311"], robot)
    results = {}
    try:
        if not wait_until(lambda: net.robot.run(["rosnode", "list"], robot, timeout=10).returncode == 0, 20):
            raise SystemExit("rosmaster did not start on the robot")
        for kind in what:
            args = [kind, "/fast"] if kind == "hz" else [kind, "/image", "--noarr"]
            tools = {"rostool": [VENV_PYTHON, "-m", "rostool", "--ros1", "topic", *args],
                     "real": ["rostopic", *args]}  # fmt: skip
            publisher = [DEBIAN_PYTHON, "-c", PUBLISHER, "1"]
            results[kind] = scenario(net, kind, publisher, robot, tools, envs, seconds)
    finally:
        master.stop()
    return results


def ratio(ours: float, real: float) -> str:
    return f"{ours / real:.2f}" if real and real == real and ours == ours else "—"


def table(summary: dict[str, Any]) -> str:
    rows = ["| scenario | rostool | real tool | ratio |", "|---|---|---|---|"]

    def row(label: str, key: str, text: str) -> None:
        ours, real = got["rostool"], got["real"]
        # an error below 0.05 % is the noise of comparing two windows: no ratio
        tiny = key == "error_pct" and max(ours[key], real[key]) < 0.05
        rows.append(f"| {name}: {label} | {text.format(**ours)} | {text.format(**real)} | "
                    f"{'both < 0.05 %' if tiny else ratio(ours[key], real[key])} |")  # fmt: skip

    for ros, real_name in (("ros2", "ros2"), ("ros1", "rostopic")):
        for kind, got in summary.get(ros, {}).items():
            name = f"ROS {ros[-1]} `topic {kind}` ({real_name})"
            sent = f"{got['true_rate']:.1f} Hz sent"
            if kind == "hz":
                row(f"rate error vs {sent}", "error_pct", "{error_pct:.3f} % ({rate:.1f} Hz)")
            else:
                row(
                    f"msgs/s of {sent} (printed, missing)",
                    "msgs_per_s",
                    "{msgs_per_s:.1f} ({messages}, {missing})",
                )
                row("first message published after start, s", "first_s", "{first_s:.2f}")
            row("CPU s", "cpu_s", "{cpu_s:.2f}")
    return "\n".join(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("what", nargs="*", metavar="hz|echo", help="scenarios (default: both)")
    parser.add_argument("--ros", choices=("1", "2", "both"), default="both")
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--json", action="store_true", help="print a JSON summary instead of the table")
    args = parser.parse_args()
    if set(args.what) - {"hz", "echo"}:
        parser.error(f"unknown scenario: {sorted(set(args.what) - {'hz', 'echo'})} (hz, echo)")
    what = [w for w in ("hz", "echo") if w in (args.what or ["hz", "echo"])]
    if os.geteuid() != 0:
        sys.exit("bench_across_machines.py needs root: it makes network namespaces (ip netns)")
    reason = netns_missing()
    if reason:
        sys.exit(f"bench_across_machines.py: no private machines here: {reason}")
    if args.ros != "1" and not ROS2.exists():
        sys.exit(f"the real ros2 (ros2cli Jazzy) is missing at {ROS2}: run ./test.sh")
    if args.ros != "2" and not (shutil.which("rosmaster") and shutil.which("rostopic")):
        sys.exit("Debian's ROS 1 (rosmaster, rostopic) is missing: run ./test.sh as root")
    tmp = Path(tempfile.mkdtemp(prefix="rostool-bench-machines-"))
    summary: dict[str, Any] = {"seconds": args.seconds, "cores": os.cpu_count()}
    try:
        with private_network() as net:
            if args.ros in ("2", "both"):
                summary["ros2"] = bench_ros2(net, what, args.seconds, tmp)
            if args.ros in ("1", "both"):
                summary["ros1"] = bench_ros1(net, what, args.seconds, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    summary["load_average"] = os.getloadavg()[0]
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(table(summary))
        print(f"window {args.seconds:g} s per pair; load average at end {summary['load_average']:.1f}")


if __name__ == "__main__":
    main()
