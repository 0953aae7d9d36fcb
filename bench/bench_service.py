"""Service calls: `rostool service call` vs Debian's `rosservice call`, and rostool's client library vs a
rospy ServiceProxy loop, all against the book's rospy sum_two_ints server.

    .venv/bin/python bench/bench_service.py [--cli-runs 15] [--calls 2000] [--repeat 5]

Starts Debian's rosmaster on a free 127.0.0.1 port and a rospy SumTwoInts server (classes generated from
the .srv with Debian's genpy, as the tests do). CLI: wall time of each command as a new process (median).
Library: round trips in a loop after a warm-up. One connection per call: rospy's ServiceProxy also asks
the master for the address each time; rostool's ServiceClient is measured both with that lookup per call
and with the address looked up once (its normal use). Then over one persistent connection each.
Prints times and ratios (rostool / Debian: below 1 means rostool is faster, for calls/s above 1).
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tests.support import (  # the repository root is on the path only now
    DEBIAN_PYTHON,
    debian_env,
    free_port,
    interface_workspace,
    master_answers,
    ros1_env,
    with_genpy_classes,
)

SERVER = """
import rospy
from sum_two_numbers.srv import SumTwoInts, SumTwoIntsResponse
rospy.init_node('sum_server')
rospy.Service('sum_two_ints', SumTwoInts, lambda req: SumTwoIntsResponse(req.a + req.b))
print("READY", flush=True)
rospy.spin()
"""

ROSPY_LOOP = """
import sys, time, rospy
from sum_two_numbers.srv import SumTwoInts
calls, persistent = int(sys.argv[1]), sys.argv[2] == "1"
rospy.init_node("bench_client", anonymous=True)
proxy = rospy.ServiceProxy("/sum_two_ints", SumTwoInts, persistent=persistent)
for i in range(50):
    proxy(i, i)
began = time.perf_counter()
for i in range(calls):
    assert proxy(i, 1).sum == i + 1
print(time.perf_counter() - began)
"""


def cli_median(command: list[str], env: dict[str, str], runs: int) -> float:
    times = []
    for _ in range(runs):
        began = time.perf_counter()
        done = subprocess.run(command, env=env, capture_output=True, text=True)
        times.append(time.perf_counter() - began)
        if done.stdout != "sum: 15\n":
            raise SystemExit(f"{command[0]} failed: {done.stdout!r} {done.stderr!r}")
    return statistics.median(times)


def our_loop(env: dict[str, str], workspace: Path, calls: int, mode: str) -> float:
    """mode: "persistent" (one connection), "connect" (a connection per call to the address looked up
    once), "lookup" (a master lookup and a connection per call: what rospy's ServiceProxy does)."""
    from rostool.graph.ros1.master_client import MasterClient
    from rostool.graph.ros1.services import ServiceClient, lookup
    from rostool.interfaces.sources import Interfaces
    from rostool.interfaces.srv import load_service

    srv = load_service(Interfaces([workspace]), "sum_two_numbers/SumTwoInts")
    master = MasterClient(env["ROS_MASTER_URI"], "/bench_client")
    request_class = srv.request.message_class()
    uri = lookup(master, "/sum_two_ints")

    def one_call(client: ServiceClient, i: int, b: int) -> int:
        if mode == "lookup":
            client.uri = lookup(master, "/sum_two_ints")
        return int(client.call(request_class(a=i, b=b)).sum)

    persistent = mode == "persistent"
    with ServiceClient(
        "/sum_two_ints", uri, srv, "/bench_client", persistent=persistent, timeout=10
    ) as client:
        for i in range(50):
            one_call(client, i, i)
        began = time.perf_counter()
        for i in range(calls):
            if one_call(client, i, 1) != i + 1:
                raise SystemExit("wrong sum")
        return time.perf_counter() - began


def rospy_loop(env: dict[str, str], calls: int, persistent: bool) -> float:
    done = subprocess.run(
        [DEBIAN_PYTHON, "-c", ROSPY_LOOP, str(calls), "1" if persistent else "0"],
        env=debian_env(env), capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"rospy loop failed: {done.stderr}")
    return float(done.stdout.strip().splitlines()[-1])


def _row(name: str, seconds: float, calls: int) -> str:
    return f"  {name:31}{seconds / calls * 1e6:8.1f} us/call {calls / seconds:8.0f} calls/s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli-runs", type=int, default=15)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=5, help="library loops: median of this many runs")
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_service_"))
    (tmp / "home").mkdir()
    env = ros1_env(free_port(), tmp / "home")
    src = interface_workspace(
        tmp / "catkin_ws", {"sum_two_numbers/srv/SumTwoInts.srv": "int64 a\nint64 b\n---\nint64 sum\n"}
    )
    env = with_genpy_classes(env, src, tmp)
    port = env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    master = subprocess.Popen(["rosmaster", "--core", "-p", port], env=debian_env(env),
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    server = None
    try:
        while not master_answers(env["ROS_MASTER_URI"]):
            time.sleep(0.05)
        server = subprocess.Popen([DEBIAN_PYTHON, "-c", SERVER], env=debian_env(env), stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL, text=True)  # fmt: skip
        assert server.stdout is not None and server.stdout.readline().strip() == "READY"
        time.sleep(0.5)
        ours_cli = cli_median([sys.executable, "-m", "rostool", "service", "call", "/sum_two_ints", "7", "8"],
                              env, args.cli_runs)  # fmt: skip
        theirs_cli = cli_median(
            ["rosservice", "call", "/sum_two_ints", "7", "8"], debian_env(env), args.cli_runs
        )
        print(f"CLI, one call per process (median of {args.cli_runs}):")
        print(f"  {'rosservice call':31}{theirs_cli * 1000:8.1f} ms   {1 / theirs_cli:6.2f} calls/s")
        print(f"  {'rostool service call':31}{ours_cli * 1000:8.1f} ms   {1 / ours_cli:6.2f} calls/s   "
              f"ratio time {ours_cli / theirs_cli:.2f}, calls/s {theirs_cli / ours_cli:.2f}x")  # fmt: skip
        for persistent in (False, True):
            kind = "persistent connection" if persistent else "one connection per call"
            modes = [("", "persistent")] if persistent else [(" (lookup)", "lookup"), ("", "connect")]
            theirs_runs: list[float] = []
            ours_runs: dict[str, list[float]] = {mode: [] for _label, mode in modes}
            for _ in range(args.repeat):  # interleaved, so load changes hit both sides alike
                theirs_runs.append(rospy_loop(env, args.calls, persistent))
                for _label, mode in modes:
                    ours_runs[mode].append(our_loop(env, src.parent, args.calls, mode))
            theirs = statistics.median(theirs_runs)
            print(f"library loop, {args.calls} calls, {kind} (median of {args.repeat}):")
            print(_row("rospy ServiceProxy", theirs, args.calls))
            for label, mode in modes:
                ours = statistics.median(ours_runs[mode])
                print(
                    _row(f"rostool ServiceClient{label}", ours, args.calls) + f"   ratio {theirs / ours:.2f}x"
                )
    finally:
        for proc in (server, master):
            if proc is not None:
                proc.send_signal(2)
                proc.wait(10)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
