"""Start-up of the verbs that open endpoints, against real rclpy nodes (Fast DDS, loopback) and beside the
real `ros2` (with its own warm daemon), in one run (issue 21):

- `topic echo /t --once` of a 10 Hz talker: wall time of a fresh process (target <= 1.0 s);
- `topic pub --once`: wall time, and whether the real listener heard that very message;
- `bag record /t` for 3 s (SIGINT 3 s after the process started) at 10 Hz: messages in the bag, read
  with the mcap library (target >= 29); beside it `topic echo /t` for 3 s, rostool's and ros2's, counted.

    .venv/bin/python bench/bench_startup.py [--distro jazzy|kilted] [--runs 5] [--backend dds|rclpy]...
        [--daemon] [--what echo|pub|record|phases|linger|call|relays]...

With --daemon, `topic echo` (and hz, bw) read through the daemon's relay: its reader in the warm graph, the
messages streamed over the Unix socket; `relays` runs 10x --runs relayed echoes and shows the daemon's
memory and threads before and after.

Each call is a new process, as a user's shell runs it; the tools alternate, so a drift of the machine's
speed touches all of them. Without --daemon rostool asks the graph directly (ROSTOOL_NO_DAEMON=1); with it,
through its warm graph daemon (started before the peers, as bench_daemon.py does).
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from _graph import VENV_PYTHON, ros2_env, tear_down_ros2

from tests.ros2_peers import PEERS_DIR, RclpyPeer, assert_loopback_only, peer_env

RECORD_SECONDS = 3.0
Tool = tuple[str, list[str], dict[str, str]]


def timed(command: list[str], env: dict[str, str], timeout: float = 30) -> tuple[float, str, int]:
    start = time.perf_counter()
    try:
        done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return time.perf_counter() - start, "", -1
    return time.perf_counter() - start, done.stdout, done.returncode


def for_seconds(command: list[str], env: dict[str, str], seconds: float) -> str:
    """Run `command`, SIGINT it `seconds` after it started, and return its stdout."""
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(seconds)
    proc.send_signal(signal.SIGINT)
    try:
        return proc.communicate(timeout=30)[0]
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.communicate()[0]


def bag_messages(directory: Path) -> int:
    """Messages in a rosbag2 directory's .mcap files (the mcap library's reader, not rostool's)."""
    from mcap.reader import make_reader

    total = 0
    for path in directory.glob("*.mcap"):
        with path.open("rb") as stream:
            summary = make_reader(stream).get_summary()
            total += summary.statistics.message_count if summary and summary.statistics else 0
    return total


def row(label: str, values: list[float], unit: str = "s", extra: str = "") -> str:
    if not values:
        return f"| {label} | - | - | - | {extra} |"
    fmt = "{:.2f}" if unit == "s" else "{:.0f}"
    median, low, high = (fmt.format(v) for v in (statistics.median(values), min(values), max(values)))
    return f"| {label} | {median} {unit} | {low} | {high} | {extra} |"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--distro", default="jazzy", choices=("jazzy", "kilted"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--backend", action="append", choices=("dds", "rclpy"))
    parser.add_argument("--daemon", action="store_true", help="rostool through its warm graph daemon")
    parser.add_argument(
        "--what", action="append", choices=("echo", "pub", "record", "phases", "linger", "call", "relays")
    )
    args = parser.parse_args()
    backends = args.backend or ["dds", "rclpy"]
    what = args.what or ["echo", "pub", "record"]
    scratch = Path(tempfile.mkdtemp(prefix="rtb"))
    run_dir = scratch / "run"
    run_dir.mkdir(mode=0o700)
    env = {**ros2_env(), "XDG_RUNTIME_DIR": str(run_dir), "XDG_STATE_HOME": str(scratch / "state")}
    env["ROSTOOL_NO_DAEMON"] = "" if args.daemon else "1"
    fast = peer_env(env, scratch)  # ros2's (and the rclpy backend's) environment: Fast DDS on loopback
    ros2_dir = next(
        PEERS_DIR / d / "bin" for d in (args.distro, "jazzy") if (PEERS_DIR / d / "bin" / "ros2").exists()
    )
    ros2 = str(ros2_dir / "ros2")  # the peer venvs install the real ros2 for Jazzy only
    tools: list[Tool] = []
    for backend in backends:
        python = VENV_PYTHON if backend == "dds" else str(PEERS_DIR / args.distro / "bin" / "python")
        command = [python, "-m", "rostool", "--ros2", "--ros2-backend", backend]
        tools.append((f"rostool {backend}", command, env if backend == "dds" else fast))
    tools.append((f"ros2 ({ros2_dir.parent.name})", [ros2], fast))
    print(f"{args.distro} peers (rclpy, Fast DDS, loopback); rostool {'with' if args.daemon else 'without'} "
          f"its daemon; load average at start {os.getloadavg()[0]:.1f}")  # fmt: skip
    subprocess.run([ros2, "daemon", "start"], env=fast, capture_output=True, timeout=60)
    if args.daemon:
        for _label, command, tool_env in tools[:-1]:
            subprocess.run([*command, "daemon", "start"], env=tool_env, capture_output=True, timeout=60)
    talker = RclpyPeer(args.distro, env, scratch, ["--name", "talker", "--talk", "/t", "--rate", "10"])
    listener = RclpyPeer(
        args.distro,
        env,
        scratch,
        [
            "--name",
            "listener",
            "--listen",
            "/heard",
            "--service",
            "/set_flag",
            "--action",
            "/fibonacci",
            "--step",
            "0.01",
            "--params",
        ],
    )
    peers = [talker, listener]
    try:
        for peer in peers:
            peer.wait_for("ready", timeout=60)
        time.sleep(2.0)  # the peers discover each other and the daemons before anything is timed
        print("| what | median | min | max | notes |\n|---|---|---|---|---|")
        if "echo" in what:
            bench_echo(tools, args.runs)
        if "pub" in what:
            bench_pub(tools, args.runs, listener)
        if "record" in what:
            bench_record(tools, args.runs, scratch)
        if "phases" in what:
            bench_phases(tools, args.runs)
        if "call" in what:
            bench_calls(tools, args.runs, listener)
        if "relays" in what and args.daemon:
            bench_relays(tools, args.runs * 10)
        if "linger" in what:
            bench_linger(args.distro, env, scratch, args.runs)
    finally:
        tear_down_ros2(env, fast, ros2, peers, scratch)


def bench_echo(tools: list[Tool], runs: int) -> None:
    times: dict[str, list[float]] = {label: [] for label, _c, _e in tools}
    good: dict[str, int] = dict.fromkeys(times, 0)
    for _ in range(runs):
        for label, command, env in tools:
            seconds, out, code = timed([*command, "topic", "echo", "/t", "--once"], env)
            times[label].append(seconds)
            good[label] += code == 0 and "data: hello" in out
    for label, values in times.items():
        print(row(f"{label} topic echo /t --once", values, extra=f"{good[label]}/{runs} printed a message"))


def bench_relays(tools: list[Tool], count: int) -> None:
    """`count` relayed `topic echo --once` one after the other: the daemon's memory and threads before and
    after (a relay's reader, threads and queue must all go with its verb), and its relays left open."""
    for label, command, env in tools:
        if not label.startswith("rostool"):
            continue
        first = _daemon(command, env)
        good = sum(timed([*command, "topic", "echo", "/t", "--once"], env)[2] == 0 for _ in range(count))
        last = _daemon(command, env)
        same = "same daemon" if first["pid"] == last["pid"] else "REPLACED (another build): not comparable"
        print(
            f"| {label}: {count} relayed echo --once | RSS {first['VmRSS']} -> {last['VmRSS']} | threads "
            f"{first['Threads']} -> {last['Threads']} | relays left {len(last['relays'])}, {same} | "
            f"{good}/{count} ok |"
        )


def _daemon(command: list[str], env: dict[str, str]) -> dict[str, Any]:
    """The daemon's status with its process's VmRSS and Threads."""
    import json

    done = subprocess.run([*command, "daemon", "status", "--json"], env=env, capture_output=True, text=True,
                          timeout=30)  # fmt: skip
    status: dict[str, Any] = json.loads(done.stdout)
    lines = Path(f"/proc/{status['pid']}/status").read_text().splitlines()
    status.update({key: value.strip() for key, _, value in (line.partition(":") for line in lines)})
    return status


def bench_pub(tools: list[Tool], runs: int, listener: RclpyPeer) -> None:
    times: dict[str, list[float]] = {label: [] for label, _c, _e in tools}
    heard: dict[str, int] = dict.fromkeys(times, 0)
    for run in range(runs):
        for label, command, env in tools:
            text = f"{label.replace(' ', '-')}-{run}"
            verb = ["topic", "pub", "--once", "/heard", "std_msgs/msg/String", f"{{data: '{text}'}}"]
            seconds, _out, _code = timed([*command, *verb], env)
            times[label].append(seconds)
            try:
                listener.wait_for("heard", lambda e, t=text: e["data"] == t, timeout=3.0)  # type: ignore[misc]
                heard[label] += 1
            except AssertionError:
                pass
    for label, values in times.items():
        print(row(f"{label} topic pub --once", values, extra=f"heard {heard[label]}/{runs}"))


def bench_record(tools: list[Tool], runs: int, scratch: Path) -> None:
    kept: dict[str, list[float]] = {}
    for run in range(runs):
        for label, command, env in tools:
            if label.startswith("rostool"):
                bag = scratch / f"bag_{label.replace(' ', '_')}_{run}"
                for_seconds([*command, "bag", "record", "/t", "-o", str(bag)], env, RECORD_SECONDS)
                kept.setdefault(f"{label} bag record /t (Ctrl+C 3 s after start)", []).append(
                    bag_messages(bag)
                )
                timed_bag = scratch / f"duration_{label.replace(' ', '_')}_{run}"
                verb = ["bag", "record", "/t", "--duration", f"{RECORD_SECONDS:g}", "-o", str(timed_bag)]
                timed([*command, *verb], env, timeout=60)
                kept.setdefault(f"{label} bag record /t --duration 3", []).append(bag_messages(timed_bag))
            out = for_seconds([*command, "topic", "echo", "/t"], env, RECORD_SECONDS)
            kept.setdefault(f"{label} topic echo /t", []).append(_count_lines(out, "data: hello"))
    for label, values in sorted(kept.items(), key=_record_order):
        print(row(f"{label}, {RECORD_SECONDS:g} s of 10 Hz", values, unit="msgs"))


# One fresh process: seconds from its start to each step of a subscription, from inside (no daemon).
PHASES = r"""
import sys, threading, time
start = time.perf_counter()
from rostool.graph import open_graph
imported = time.perf_counter()
graph = open_graph(2, "rostool", (), sys.argv[1], use_daemon=False)
opened = time.perf_counter()
got, seen = threading.Event(), []
graph.subscribe("/t", lambda m: got.set(), print)
while not seen and not got.is_set():
    graph.wait_for_newcomers(0.0)
    if any(v.is_writer for v in graph.topic_views("/t")):
        seen.append(time.perf_counter())
    time.sleep(0.002)
got.wait(30)
first = time.perf_counter()
graph.close()
print(imported - start, opened - start, (seen or [first])[0] - start, first - start)
"""


def bench_phases(tools: list[Tool], runs: int) -> None:
    """Where an echo's time goes inside the process (interpreter start not included)."""
    steps = ("import rostool.graph", "graph opened", "publisher discovered", "first message")
    for label, command, env in tools:
        if not label.startswith("rostool"):
            continue
        found: list[list[float]] = [[] for _ in steps]
        for _ in range(runs):
            done = subprocess.run([command[0], "-c", PHASES, command[-1]], env=env, capture_output=True,
                                  text=True, timeout=60)  # fmt: skip
            values = [float(v) for v in done.stdout.split()[-4:]] if done.returncode == 0 else []
            for column, value in zip(found, values, strict=False):
                column.append(value)
        for step, values in zip(steps, found, strict=True):
            print(row(f"{label}: in-process, {step} after", values))


def bench_calls(tools: list[Tool], runs: int, server: RclpyPeer) -> None:
    """param get, service call and action send_goal of the real node's servers: wall time, and whether it
    answered."""
    goal = ["action", "send_goal", "/fibonacci", "test_msgs/action/Fibonacci", "{order: 3}"]
    verbs = {
        "param get": (["param", "get", "/listener", "count"], "Integer value is: 3"),
        "service call": (["service", "call", "/set_flag", "std_srvs/srv/SetBool", "{data: true}"], "success"),
        "action send_goal": (goal, "SUCCEEDED"),
    }
    for name, (verb, answer) in verbs.items():
        times: dict[str, list[float]] = {label: [] for label, _c, _e in tools}
        good: dict[str, int] = dict.fromkeys(times, 0)
        for _ in range(runs):
            for label, command, env in tools:
                seconds, out, code = timed([*command, *verb], env)
                times[label].append(seconds)
                good[label] += code == 0 and answer in out
        for label, values in times.items():
            print(row(f"{label} {name}", values, extra=f"{good[label]}/{runs} answered"))
    served = len(server.of("service"))
    print(f"(the server logged {served} service requests)")


NO_KEYHASH = (
    '<CycloneDDS><Domain Id="any"><Internal><GenerateKeyhash>false</GenerateKeyhash></Internal></Domain>'
    "</CycloneDDS>"
)


def bench_linger(distro: str, env: dict[str, str], scratch: Path, runs: int) -> None:
    """How long a DDS-backend rostool's reader stays in a real node's graph view after rostool exited
    (Ctrl+C), as rostool configures Cyclone and with Cyclone's default of no key hashes."""
    watcher = RclpyPeer(distro, env, scratch, ["--name", "watcher", "--watch"])
    watcher.wait_for("ready", timeout=60)

    def seen() -> bool:
        views = watcher.of("graph")
        return bool(views and views[-1]["subscribers"].get("/t"))

    try:
        for label, extra in (("as configured", {}), ("without key hashes", {"CYCLONEDDS_URI": NO_KEYHASH})):
            gone: list[float] = []
            for _ in range(runs):
                proc = subprocess.Popen([VENV_PYTHON, "-m", "rostool", "--ros2", "topic", "echo", "/t"],
                                        env={**env, **extra}, stdout=subprocess.DEVNULL,
                                        stderr=subprocess.DEVNULL)  # fmt: skip
                deadline = time.monotonic() + 30
                while not seen() and time.monotonic() < deadline:
                    time.sleep(0.05)
                proc.send_signal(signal.SIGINT)
                proc.wait(timeout=30)
                exited = time.monotonic()
                while seen() and time.monotonic() - exited < 30:
                    time.sleep(0.05)
                gone.append(time.monotonic() - exited)
            print(row(f"rostool dds reader gone from a real node's view after exit, {label}", gone,
                      extra="the node reports every 0.5 s"))  # fmt: skip
    finally:
        addresses = watcher.bound_addresses()
        watcher.stop()
        assert_loopback_only(addresses)


def _count_lines(out: str, prefix: str) -> int:
    return sum(line.startswith(prefix) for line in out.splitlines())


def _record_order(item: tuple[str, list[float]]) -> tuple[bool, str]:
    return ("bag record" not in item[0], item[0])


if __name__ == "__main__":
    main()
