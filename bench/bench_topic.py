"""`topic hz`, `topic echo` and start-up: rostool vs Debian's rostopic, side by side in one run.

.venv/bin/python bench/bench_topic.py [hz|echo|startup]...
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time

from _graph import (
    cpu_seconds,
    debian_env,
    free_port,
    loopback_env,
    median_wall,
    rostool_cmd,
    start_master,
    start_publisher,
)


def bench_hz(env: dict[str, str], count: int, rate: float) -> None:
    pub = start_publisher(env, count, rate, 2)
    ours = subprocess.Popen([*rostool_cmd("topic", "hz", "/bench", "--json")], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)  # fmt: skip
    theirs = subprocess.Popen(["rostopic", "hz", "/bench"], env=debian_env(env),
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)  # fmt: skip
    assert pub.stdout is not None
    sent_line = pub.stdout.readline()
    pub.wait()
    seconds = float(sent_line.split()[3])
    true_rate = (count - 1) / seconds
    time.sleep(2.5)
    our_cpu, their_cpu = cpu_seconds(ours.pid), cpu_seconds(theirs.pid)
    for proc in (ours, theirs):
        proc.send_signal(signal.SIGINT)
    our_out = ours.communicate()[0]
    their_out = theirs.communicate()[0]
    last = [json.loads(line) for line in our_out.splitlines() if line.startswith("{")][-1]
    their_rates = re.findall(r"average rate: ([\d.]+)", their_out)
    their_windows = re.findall(r"window: (\d+)", their_out)
    their_rate = float(their_rates[-1]) if their_rates else 0.0
    their_count = int(their_windows[-1]) if their_windows else 0
    label = f"{rate:g} msg/s" if rate else "max"
    print(f"hz {label:>11}: sent {count} at {true_rate:,.0f} msg/s")
    for name, got_count, got_rate, cpu in (
        ("rostool", last["window"], last["rate"], our_cpu),
        ("rostopic", their_count, their_rate, their_cpu),
    ):
        print(f"  {name:9} counted {got_count:>7} ({100 * (count - got_count) / count:6.2f}% missed)  "
              f"rate {got_rate:>10,.1f} ({100 * abs(got_rate - true_rate) / true_rate:6.2f}% error)  "
              f"cpu {cpu:5.2f}s")  # fmt: skip
    print(f"  cpu ratio rostool/rostopic: {our_cpu / their_cpu:.2f}")


def bench_echo(env: dict[str, str], count: int, type_name: str) -> None:
    results = {}
    for name, cmd, tool_env in (
        ("rostool", rostool_cmd("topic", "echo", "/bench"), env),
        ("rostopic", ["rostopic", "echo", "/bench"], debian_env(env)),
    ):
        pub = start_publisher(env, count, 0, 1, type_name)
        proc = subprocess.Popen(cmd, env=tool_env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        assert proc.stdout is not None
        seen, first, last = 0, 0.0, 0.0
        deadline = None
        while True:
            line = proc.stdout.readline()
            if not line:
                break
            if line == b"---\n":
                seen += 1
                last = time.perf_counter()
                if seen == 1:
                    first = last
                    deadline = last + 60
                if seen == count or (deadline and last > deadline):
                    break
            if pub.poll() is not None and seen and time.perf_counter() - last > 2:
                break
        proc.send_signal(signal.SIGINT)
        proc.wait()
        pub.send_signal(signal.SIGINT)  # lets it unregister, so the next run starts clean
        pub.wait()
        span = max(last - first, 1e-9)
        results[name] = (seen, seen / span)
        print(f"echo {type_name} {name:9}: printed {seen}/{count}, {seen / span:,.0f} msg/s to a pipe")
    ratio = results["rostool"][1] / results["rostopic"][1]
    print(f"  throughput ratio rostool/rostopic: {ratio:.2f}")


def bench_startup(env: dict[str, str]) -> None:
    ours = median_wall(rostool_cmd("topic", "list"), env)
    theirs = median_wall(["rostopic", "list"], debian_env(env))
    help_time = median_wall(rostool_cmd("--help"), env)
    script = median_wall([sys.executable.replace("python", "rostool"), "topic", "list"], env)
    print(f"startup: rostool topic list {ours:.3f}s (console script {script:.3f}s), "
          f"rostopic list {theirs:.3f}s, ratio {script / theirs:.2f}; "
          f"rostool --help {help_time:.3f}s")  # fmt: skip


def main() -> None:
    which = sys.argv[1:] or ["startup", "hz", "echo"]
    env = loopback_env(free_port())
    master = start_master(env)
    try:
        if "startup" in which:
            bench_startup(env)
        if "hz" in which:
            bench_hz(env, 10_000, 1_000)
            bench_hz(env, 100_000, 10_000)
            bench_hz(env, 200_000, 20_000)
            bench_hz(env, 300_000, 0)
        if "echo" in which:
            bench_echo(env, 20_000, "std_msgs/Int32")
            bench_echo(env, 20_000, "geometry_msgs/PoseStamped")
    finally:
        master.terminate()
        master.wait()


if __name__ == "__main__":
    main()
