"""`rostool core` against Debian's rosmaster: start-up time and XML-RPC throughput, side by side.

    .venv/bin/python bench/bench_core.py [--clients 16] [--calls 200]

Both masters run as separate processes on free 127.0.0.1 ports; the same client load hits each in turn.
Prints seconds per master and the ratio rostool / rosmaster (below 1 means rostool is faster).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
import xmlrpc.client
from collections.abc import Callable
from typing import Any

from _graph import debian_env, free_port


def answers(uri: str) -> bool:
    try:
        proxy: Any = xmlrpc.client.ServerProxy(uri)
        return bool(proxy.getPid("/bench")[0] == 1)
    except (OSError, xmlrpc.client.Error):
        return False


def start(command: list[str], env: dict[str, str], uri: str) -> tuple[subprocess.Popen[bytes], float]:
    began = time.perf_counter()
    proc = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not answers(uri):
        if proc.poll() is not None or time.perf_counter() - began > 30:
            raise SystemExit(f"{command[0]} did not start")
        time.sleep(0.005)
    return proc, time.perf_counter() - began


def load(uri: str, clients: int, calls: int) -> float:
    def client(index: int) -> None:
        proxy: Any = xmlrpc.client.ServerProxy(uri)
        caller, api = f"/bench_{index}", f"http://127.0.0.1:{10000 + index}/"
        for step in range(calls):
            proxy.setParam(caller, f"~p{step % 10}", {"value": step, "list": [1, 2, 3]})
            proxy.getParam(caller, f"~p{step % 10}")
            proxy.registerPublisher(caller, f"/topic_{step % 20}", "std_msgs/String", api)
            proxy.getSystemState(caller)

    threads = [threading.Thread(target=client, args=(i,)) for i in range(clients)]
    began = time.perf_counter()
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return time.perf_counter() - began


def measure(
    name: str, command: Callable[[int], list[str]], env: dict[str, str], args: argparse.Namespace
) -> Any:
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    proc, startup = start(command(port), {**env, "ROS_MASTER_URI": uri}, uri)
    try:
        seconds = load(uri, args.clients, args.calls)
    finally:
        proc.send_signal(2)
        proc.wait(10)
    total = args.clients * args.calls * 4
    print(
        f"{name:10} start-up {startup:6.3f} s   {total} calls in {seconds:6.3f} s ({total / seconds:7.0f}/s)"
    )
    return startup, seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=16)
    parser.add_argument("--calls", type=int, default=200)
    args = parser.parse_args()
    home = tempfile.mkdtemp(prefix="bench_core_")
    base = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    base.update(ROS_HOSTNAME="127.0.0.1", ROS_HOME=home)
    theirs = measure(
        "rosmaster", lambda port: ["rosmaster", "--core", "-p", str(port)], debian_env(base), args
    )
    ours = measure(
        "rostool", lambda port: [sys.executable, "-m", "rostool", "core", "--port", str(port)], base, args
    )
    print(f"ratio rostool/rosmaster: start-up {ours[0] / theirs[0]:.2f}, load {ours[1] / theirs[1]:.2f}")


if __name__ == "__main__":
    main()
