"""Shared helpers for tests: free ports, loopback ROS 1 environments, and Debian's real ROS 1 peers."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")
DEBIAN_PYTHON = "/usr/bin/python3"
TESTDATA = Path(__file__).resolve().parent.parent.parent / "shared" / "testdata"


def require_ros1_peers() -> None:
    """Debian's ROS 1 tools must be here; in CI their absence fails the test, elsewhere it skips."""
    ok = shutil.which("rosmaster") is not None and os.path.exists(DEBIAN_PYTHON)
    if ok:
        probe = subprocess.run(
            [DEBIAN_PYTHON, "-c", "import rospy, rostopic, rosparam, rosnode"],
            capture_output=True,
            env=debian_env({}),
        )
        ok = probe.returncode == 0
    if not ok:
        message = "Debian's ROS 1 peers (ros-core, python3-rospy) are not installed: run ./test.sh as root"
        if IN_CI:
            pytest.fail(message)
        pytest.skip(message)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def ros1_env(port: int, home: Path) -> dict[str, str]:
    """A loopback-only ROS 1 environment pointing at the master on `port`."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env.update(
        ROS_MASTER_URI=f"http://127.0.0.1:{port}",
        ROS_HOSTNAME="127.0.0.1",
        ROS_HOME=str(home),
        ROS_LOG_DIR=str(home / "log"),
        PYTHONUNBUFFERED="1",
    )
    return env


def debian_env(env: dict[str, str]) -> dict[str, str]:
    """Environment for Debian's tools: their own interpreter and dist-packages, nothing from our venv."""
    hidden = ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")
    clean = {k: v for k, v in (env or os.environ).items() if k not in hidden}
    clean["PATH"] = "/usr/bin:/bin:/usr/sbin:/sbin"
    return clean


def wait_until(predicate: Callable[[], bool], timeout: float = 10.0, interval: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(interval)
    return predicate()


def master_answers(uri: str) -> bool:
    try:
        code, _msg, _pid = xmlrpc.client.ServerProxy(uri).getPid("/test")
        return bool(code == 1)
    except (OSError, xmlrpc.client.Error):
        return False


def rostool(
    args: Sequence[str], env: dict[str, str], timeout: float = 30, input: str | None = None
) -> subprocess.CompletedProcess[str]:
    """Run the installed rostool CLI as a user would."""
    return subprocess.run(
        [sys.executable, "-m", "rostool", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        input=input,
    )


def rostool_popen(args: Sequence[str], env: dict[str, str], **kwargs: object) -> subprocess.Popen[str]:
    return subprocess.Popen(  # type: ignore[call-overload]
        [sys.executable, "-m", "rostool", *args],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def debian(
    args: Sequence[str], env: dict[str, str], timeout: float = 30, input: str | None = None
) -> subprocess.CompletedProcess[str]:
    """Run one of Debian's ROS 1 command-line tools (rostopic, rosparam, rosnode, rosbag...)."""
    return subprocess.run(
        list(args), env=debian_env(env), capture_output=True, text=True, timeout=timeout, input=input
    )


def debian_popen(args: Sequence[str], env: dict[str, str], **kwargs: object) -> subprocess.Popen[str]:
    return subprocess.Popen(  # type: ignore[call-overload]
        list(args),
        env=debian_env(env),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def start_rospy_script(
    source: str, env: dict[str, str], tmp_path: Path, name: str, args: Sequence[str] = ()
) -> subprocess.Popen[str]:
    """Run a small rospy program with Debian's python3 (a real ROS 1 peer node)."""
    script = tmp_path / f"{name}.py"
    script.write_text(source)
    return debian_popen([DEBIAN_PYTHON, str(script), *args], env)


def stop(proc: subprocess.Popen[str], timeout: float = 5.0) -> tuple[str, str]:
    """Interrupt a process like Ctrl+C would, then collect its output."""
    if proc.poll() is None:
        proc.send_signal(2)
        try:
            return proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
    return proc.communicate()
