"""`rostool bag record` vs Debian's `rosbag record`, side by side on the same rospy publisher.

    .venv/bin/python bench/bench_bag_record.py [--seconds 3] [--rates 1000,5000,10000,20000,50000]

Debian's rosmaster on a free 127.0.0.1 port; both recorders subscribe to /bench at the same time and
write to the same disk (a temporary directory). A rospy publisher (Debian's python3: a real ROS 1 peer,
queue_size 10000 per subscriber, so a subscriber that cannot keep up loses messages at the publisher,
as in a real graph) waits for both, then:

1. small messages: publishes RATE std_msgs/Int32 per second (numbered, in 1 ms bursts) for SECONDS; the
   bags are read back and the messages missing from each are counted. Reported per rate: the rate the
   publisher achieved and each recorder's loss; the result is the highest rate each recorded with zero
   loss.
2. 1 MB messages: std_msgs/UInt8MultiArray of 1 MiB as fast as the publisher can (queue_size 4) for
   SECONDS; reported: MB/s each recorder wrote (messages in the bag x 1 MiB / publishing time).
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import xmlrpc.client
from pathlib import Path
from typing import Any

from _graph import debian_env, free_port

PUBLISHER = """
import sys, time
import rospy
from std_msgs.msg import Int32, UInt8MultiArray
mode, rate, seconds, base = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
rospy.init_node('bench_pub', anonymous=True)
if mode == 'small':
    pub = rospy.Publisher('/bench', Int32, queue_size=10000)
else:
    pub = rospy.Publisher('/bench', UInt8MultiArray, queue_size=4)
while pub.get_num_connections() < 2:
    time.sleep(0.01)
time.sleep(1.0)
start = time.time()
sent = 0
if mode == 'small':
    total = int(rate * seconds)
    while sent < total:
        due = start + sent / rate
        now = time.time()
        if now < due:
            time.sleep(min(due - now, 0.001))
            continue
        burst = min(total, int((now - start) * rate) + 1)
        while sent < burst:
            pub.publish(Int32(data=base + sent))
            sent += 1
else:
    payload = bytes(1 << 20)
    msg = UInt8MultiArray(data=payload)
    while time.time() - start < seconds:
        pub.publish(msg)
        sent += 1
elapsed = time.time() - start
print('%d %.6f' % (sent, elapsed), flush=True)
time.sleep(2.0)
"""


def subscribers(uri: str) -> int:
    proxy: Any = xmlrpc.client.ServerProxy(uri)
    _code, _msg, (_pubs, subs, _srvs) = proxy.getSystemState("/bench")
    return sum(len(nodes) for topic, nodes in subs if topic == "/bench")


def count(path: Path) -> tuple[int, list[int]]:
    """(messages, Int32 values when small) of a bag, read with rosbags."""
    import struct

    from rosbags.rosbag1 import Reader

    values = []
    total = 0
    with Reader(path) as reader:
        for conn, _t, data in reader.messages():
            if conn.topic == "/bench":
                total += 1
                if len(data) == 4:
                    values.append(struct.unpack("<i", data)[0])
    return total, values


def run_round(
    work: Path, env: dict[str, str], mode: str, rate: float, seconds: float, publishers: int = 1
) -> dict[str, Any]:
    uri = env["ROS_MASTER_URI"]
    ours_path, theirs_path = work / f"ours_{mode}_{rate:g}.bag", work / f"theirs_{mode}_{rate:g}.bag"
    ours = subprocess.Popen(
        [sys.executable, "-m", "rostool", "bag", "record", "-q", "/bench", "-O", str(ours_path)],
        env=env,
        stderr=subprocess.PIPE,
        text=True,
    )
    theirs = subprocess.Popen(
        ["rosbag", "record", "-q", "/bench", "-O", str(theirs_path)],
        env=debian_env(env),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    script = work / "publisher.py"
    script.write_text(PUBLISHER)
    deadline = time.monotonic() + 30
    while subscribers(uri) < 2:
        if time.monotonic() > deadline:
            raise SystemExit("the recorders did not subscribe")
        time.sleep(0.05)
    procs = [
        subprocess.Popen(
            ["/usr/bin/python3", str(script), mode, str(rate / publishers), str(seconds), str(k * 10**8)],
            env=debian_env(env),
            stdout=subprocess.PIPE,
            text=True,
        )
        for k in range(publishers)
    ]
    sent, elapsed = 0, 0.0
    for publisher in procs:
        assert publisher.stdout is not None
        sent_text = publisher.stdout.readline().split()
        sent, elapsed = sent + int(sent_text[0]), max(elapsed, float(sent_text[1]))
    time.sleep(1.5)
    for proc in (ours, theirs):
        proc.send_signal(signal.SIGINT)
    _out, err = ours.communicate(timeout=120)
    theirs.wait(timeout=120)
    for publisher in procs:
        publisher.wait(timeout=30)
    if err.strip():
        print(err.strip(), file=sys.stderr)
    result: dict[str, Any] = {"sent": sent, "elapsed": elapsed}
    for name, path in (("rostool", ours_path), ("rosbag", theirs_path)):
        total, values = count(path)
        result[name] = total
        if mode == "small":
            result[f"{name}_missing"] = sent - len(set(values))
        path.unlink()
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--rates", default="1000,5000,10000,20000,50000")
    parser.add_argument("--big-rounds", type=int, default=3)
    parser.add_argument("--publishers", type=int, default=1, help="rospy publishers sharing the small rate")
    args = parser.parse_args()
    rates = [float(r) for r in args.rates.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        port = free_port()
        env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
        env.update(ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOSTNAME="127.0.0.1", ROS_HOME=str(work))
        master = subprocess.Popen(
            ["rosmaster", "--core", "-p", str(port)],
            env=debian_env(env),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            deadline = time.monotonic() + 20
            while True:
                try:
                    subscribers(env["ROS_MASTER_URI"])
                    break
                except OSError:
                    if time.monotonic() > deadline:
                        raise SystemExit("rosmaster did not start") from None
                    time.sleep(0.05)
            print("small messages (std_msgs/Int32):")
            print("| target msgs/s | achieved msgs/s | rostool missing | rosbag missing |")
            print("|---|---|---|---|")
            best = {"rostool": 0.0, "rosbag": 0.0}
            lost_once: set[str] = set()
            for rate in rates:
                r = run_round(work, env, "small", rate, args.seconds, args.publishers)
                achieved = r["sent"] / r["elapsed"]
                print(f"| {rate:,.0f} | {achieved:,.0f} | {r['rostool_missing']} | {r['rosbag_missing']} |")
                for name in best:  # the highest rate reached before the first loss
                    if r[f"{name}_missing"]:
                        lost_once.add(name)
                    elif name not in lost_once:
                        best[name] = max(best[name], achieved)
            print(
                f"\nhighest rate with zero loss: rostool {best['rostool']:,.0f} msgs/s, "
                f"rosbag {best['rosbag']:,.0f} msgs/s (ratio {best['rostool'] / max(best['rosbag'], 1):.2f}x)"
            )
            if args.big_rounds <= 0:
                return
            mib = 1.048576
            print("\n1 MiB messages (std_msgs/UInt8MultiArray):")
            print("| round | publisher sent | rostool msgs | rostool MB/s | rosbag msgs | rosbag MB/s |")
            print("|---|---|---|---|---|---|")
            speeds: dict[str, list[float]] = {"rostool": [], "rosbag": []}
            for index in range(args.big_rounds):
                r = run_round(work, env, "big", 0, args.seconds)
                for name in speeds:
                    speeds[name].append(r[name] * mib / r["elapsed"])
                print(
                    f"| {index + 1} | {r['sent']} | {r['rostool']} | {speeds['rostool'][-1]:.0f} | "
                    f"{r['rosbag']} | {speeds['rosbag'][-1]:.0f} |"
                )
            ours, theirs = statistics.median(speeds["rostool"]), statistics.median(speeds["rosbag"])
            ratio = ours / max(theirs, 1e-9)
            print(f"\nmedian MB/s: rostool {ours:.0f}, rosbag {theirs:.0f}, ratio {ratio:.2f}x")
        finally:
            master.terminate()
            master.wait(10)


if __name__ == "__main__":
    main()
