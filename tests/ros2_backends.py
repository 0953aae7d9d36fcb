"""Run one ROS 2 test on both backends: rostool's DDS (the test venv) and rclpy (the distro's peer venv,
where test.sh installs rostool too, with the peers' loopback-only Fast DDS profile).

    def test_x(tool: Tool, tool_popen: ToolPopen) -> None: ...   # runs as [<distro>-dds] and [<distro>-rclpy]
"""

from __future__ import annotations

import re
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.ros2_peers import WarmDaemon, rostool_rclpy, rostool_rclpy_popen
from tests.support import rostool, rostool_popen

BACKENDS = ("dds", "rclpy")
Tool = Callable[..., "subprocess.CompletedProcess[str]"]
ToolPopen = Callable[[list[str]], "subprocess.Popen[str]"]
# the middleware's own log lines (Jazzy's rmw_fastrtps warns that FASTRTPS_DEFAULT_PROFILES_FILE, which the
# peers' environment sets for Fast DDS 2, is deprecated): the user's RMW speaking, not rostool
RMW_LOG = re.compile(r"^\[(WARN|INFO)\] \[[\d.]+\] \[rmw_")
# Fast DDS's own log lines, colored even into a pipe (Kilted's Fast DDS 3 under load: "2026-11-28
# 01:09:06.099 [TYPELOOKUP_SERVICE_REPLY_LISTENER Error] Error registering remote type: ...")
FASTDDS_LOG = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d+ \[\w+ (Error|Warning|Info)\] ")
ANSI = re.compile(r"\x1b\[[\d;]*m")


def middleware_line(line: str) -> bool:
    """Whether a stderr line is the middleware's own log (the user's RMW speaking, not rostool)."""
    return bool(RMW_LOG.match(line) or FASTDDS_LOG.match(ANSI.sub("", line)))


def rostool_lines(stderr: str) -> list[str]:
    """stderr's lines without the RMW's own log lines."""
    return [line for line in stderr.strip().splitlines() if not middleware_line(line)]


@pytest.fixture(params=BACKENDS)
def backend(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def tool(backend: str, graph_env: dict[str, str], tmp_path: Path, distro: str) -> Tool:
    """tool(args, timeout=30): rostool on the test's backend, in the test's graph; the result's
    `stderr_lines` are stderr's lines without the RMW's own log lines."""

    def run(args: list[str], timeout: float = 30) -> subprocess.CompletedProcess[str]:
        if backend == "rclpy":
            done = rostool_rclpy(args, graph_env, tmp_path, distro, timeout=timeout)
        else:
            done = rostool(args, graph_env, timeout)
        done.stderr_lines = rostool_lines(done.stderr)  # type: ignore[attr-defined]
        return done

    return run


@pytest.fixture
def served_tool(backend: str, graph_env: dict[str, str], tmp_path: Path, distro: str) -> Iterator[ServedTool]:
    """tool(args, timeout=30) as `tool` gives it, with the listings answered by a warm graph daemon of the
    test's backend (`served_tool.daemon`; stopped at the end). Keep a direct test of each verb too."""

    def popen(args: list[str], env: dict[str, str]) -> subprocess.Popen[str]:
        if backend == "rclpy":
            return rostool_rclpy_popen(args, env, tmp_path, distro)
        return rostool_popen(["--ros2", *args], env)

    daemon = WarmDaemon(graph_env, popen)

    def run(args: list[str], timeout: float = 30) -> subprocess.CompletedProcess[str]:
        if backend == "rclpy":
            done = rostool_rclpy(args, daemon.env, tmp_path, distro, timeout=timeout)
        else:
            done = rostool(args, daemon.env, timeout)
        done.stderr_lines = rostool_lines(done.stderr)  # type: ignore[attr-defined]
        return done

    served = ServedTool(run, daemon)
    yield served
    left = daemon.stop()
    assert not left, f"graph daemons still running after `daemon stop --all`: {left}"


class ServedTool:
    def __init__(self, run: Tool, daemon: WarmDaemon) -> None:
        self.run = run
        self.daemon = daemon

    def __call__(self, args: list[str], timeout: float = 30) -> subprocess.CompletedProcess[str]:
        return self.run(args, timeout=timeout)


@pytest.fixture
def tool_popen(backend: str, graph_env: dict[str, str], tmp_path: Path, distro: str) -> ToolPopen:
    def start(args: list[str]) -> subprocess.Popen[str]:
        if backend == "rclpy":
            return rostool_rclpy_popen(args, graph_env, tmp_path, distro)
        return rostool_popen(args, graph_env)

    return start
