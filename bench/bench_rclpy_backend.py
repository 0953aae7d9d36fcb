"""The rclpy backend against the DDS backend, both against the same real rclpy publisher (Fast DDS), with a
plain rclpy subscriber (raw=True, one thread: what `ros2 topic hz` runs) as the anchor.

    .venv/bin/python bench/bench_rclpy_backend.py [--distro jazzy|kilted] [hz|echo|list|call]...

hz: rate error and CPU at 1 000 and 10 000 msg/s; echo: messages printed to a pipe per second at the
publisher's top rate; list: `topic list` / `node list` wall time; call: `service call` wall time. The rclpy
backend runs in the distro's peer venv (where ./test.sh installs rostool too), as the tests run it.
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import subprocess
import tempfile
import threading
import time
from pathlib import Path

from _graph import cpu_seconds, ros2_env, rostool_cmd

from tests.ros2_peers import RclpyPeer, assert_loopback_only, peer_env, rclpy_command

BACKENDS = ("rclpy", "dds")
HZ_BURSTS = ((1_000, 10_000), (10_000, 50_000))  # (msg/s, count)
ECHO_BURST = (0, 30_000)  # as fast as the rclpy publisher goes
TMP = Path(tempfile.mkdtemp(prefix="rostool-bench-rclpy-"))


def command(backend: str, distro: str, env: dict[str, str], *args: str) -> tuple[list[str], dict[str, str]]:
    """rostool on `backend`: the rclpy one in the peer venv with the peers' environment."""
    if backend == "rclpy":
        return rclpy_command(list(args), distro), peer_env(env, TMP)
    return rostool_cmd("--ros2-backend", "dds", *args), env


def peer(distro: str, env: dict[str, str], *args: str) -> RclpyPeer:
    started = RclpyPeer(distro, env, TMP, list(args))
    started.wait_for("ready", timeout=30)
    return started


def stop_all(*peers: RclpyPeer) -> None:
    for p in peers:
        addresses = p.bound_addresses()
        p.stop()
        assert_loopback_only(addresses)


def burst(distro: str, backend: str, rate: int, count: int, verb: list[str]) -> dict[str, float]:
    """One burst from a real publisher, received by a plain rclpy subscriber and a rostool verb at once."""
    env = ros2_env()
    anchor = peer(distro, env, "--name", "raw_counter", "--raw-count", "/bench", "--depth", "1000")
    cmd, cmd_env = command(backend, distro, env, *verb)
    ours = subprocess.Popen(cmd, env=cmd_env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    out_lines: list[str] = []  # read as it comes: a full pipe would hold the verb back
    reader = threading.Thread(target=lambda: out_lines.extend(ours.stdout or []), daemon=True)
    reader.start()
    talker = peer(distro, env, "--name", "bench_pub", "--talk", "/bench", "--count", str(count),
                  "--rate", str(rate), "--subs", "2", "--depth", "1000")  # fmt: skip
    cpu_before = cpu_seconds(ours.pid)  # start-up (imports, discovery) is not the receiving
    sent = talker.wait_for("sent", timeout=180)
    time.sleep(2.5)
    cpu = cpu_seconds(ours.pid) - cpu_before
    ours.send_signal(signal.SIGINT)
    ours.wait(timeout=30)
    reader.join(10)
    counted = anchor.of("counted")[-1]
    stop_all(anchor, talker)
    true_rate = (count - 1) / sent["seconds"]
    lines = [json.loads(line) for line in out_lines if line.startswith("{")]
    span = max(counted["last"] - counted["first"], 1e-9)
    found = {"true_rate": true_rate, "cpu": cpu, "anchor_got": counted["count"],
             "anchor_rate": (counted["count"] - 1) / span}  # fmt: skip
    if verb[1] == "hz":
        found.update(got=lines[-1]["received"] if lines else 0, rate=lines[-1]["rate"] if lines else 0.0)
    else:
        found.update(got=len(lines))
    return found


def bench_hz(distro: str) -> None:
    print("| backend | sent | rclpy raw=True got | its rate error | rostool hz got | its rate error | CPU |")
    print("|---|---|---|---|---|---|---|")
    for rate, count in HZ_BURSTS:
        for backend in BACKENDS:
            r = burst(distro, backend, rate, count, ["topic", "hz", "/bench", "--json"])
            anchor_error = 100 * abs(r["anchor_rate"] - r["true_rate"]) / r["true_rate"]
            error = 100 * abs(r["rate"] - r["true_rate"]) / r["true_rate"]
            sent = f"{count:,} at {rate:,} msg/s ({r['true_rate']:,.0f})"
            print(
                f"| {backend} | {sent} | {r['anchor_got']:,} | {anchor_error:.2f} % | {r['got']:,} | "
                f"{error:.2f} % | {r['cpu']:.2f} s |",
                flush=True,
            )


def bench_echo(distro: str) -> None:
    rate, count = ECHO_BURST
    print("| backend | sent | rclpy raw=True got | rostool echo --json got | echo msgs/s | CPU |")
    print("|---|---|---|---|---|---|")
    for backend in BACKENDS:
        r = burst(distro, backend, rate, count, ["topic", "echo", "/bench", "--json"])
        # what reached the pipe, over the seconds the publisher took: the echo kept up when it is the rate
        per_second = r["got"] / (count / r["true_rate"])
        sent = f"{count:,} at {r['true_rate']:,.0f} msg/s"
        print(
            f"| {backend} | {sent} | {r['anchor_got']:,} | {r['got']:,} | {per_second:,.0f} | "
            f"{r['cpu']:.2f} s |",
            flush=True,
        )


def timed(cmd: list[str], env: dict[str, str], expected: str, runs: int) -> tuple[float, float, int]:
    times, complete = [], 0
    for _ in range(runs):
        start = time.perf_counter()
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=60)
        times.append(time.perf_counter() - start)
        complete += expected in done.stdout
    return statistics.median(times), max(times), complete


def bench_list_and_call(distro: str, what: list[str], runs: int = 5) -> None:
    env = ros2_env()
    graph = peer(distro, env, "--name", "talker", "--talk", "/chatter", "--listen", "/heard", "--params",
                 "--service", "/set_flag", "--action", "/fibonacci")  # fmt: skip
    verbs = []
    if "list" in what:
        verbs += [(["topic", "list"], "/chatter"), (["node", "list"], "/talker")]
    if "call" in what:
        verbs += [(["service", "call", "/set_flag", "std_srvs/srv/SetBool", "{data: true}"], "success=True")]
    verbs.append((["--help"], "Usage"))  # start-up alone: the interpreter and rostool's imports
    print("| verb | backend | complete | median | max |")
    print("|---|---|---|---|---|")
    for verb, expected in verbs:
        for backend in BACKENDS:
            cmd, cmd_env = command(backend, distro, env, *verb)
            median, worst, complete = timed(cmd, cmd_env, expected, runs)
            name = " ".join(verb[:2])
            row = f"| `{name}` | {backend} | {complete}/{runs} | {median:.2f} s | {worst:.2f} s |"
            print(row, flush=True)
    rclpy_import = [str(rclpy_command([], distro)[0]), "-c", "import rclpy, rclpy.node, std_msgs.msg"]
    median, worst, _ = timed(rclpy_import, peer_env(env, TMP), "", runs)
    print(f"| `import rclpy` alone | rclpy | - | {median:.2f} s | {worst:.2f} s |")
    stop_all(graph)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--distro", default="jazzy", choices=("jazzy", "kilted"))
    parser.add_argument("what", nargs="*", default=["hz", "echo", "list", "call"])
    args = parser.parse_args()
    print(f"real peers: {args.distro} rclpy on Fast DDS\n")
    if "hz" in args.what:
        bench_hz(args.distro)
        print()
    if "echo" in args.what:
        bench_echo(args.distro)
        print()
    if "list" in args.what or "call" in args.what:
        bench_list_and_call(args.distro, args.what)


if __name__ == "__main__":
    main()
