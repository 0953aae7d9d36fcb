"""Fixtures: each test gets its own master on a free loopback port."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import (
    debian_popen,
    free_port,
    master_answers,
    require_ros1_peers,
    ros1_env,
    rostool_popen,
    stop,
    wait_until,
)

# the real ROS 2 peers' fixtures (distro, graph_env, start_peer)
pytest_plugins = ("tests.ros2_peers", "tests.ros2_backends")


@pytest.fixture
def ros_env(tmp_path: Path) -> dict[str, str]:
    """Environment for a fresh loopback ROS 1 graph (no master started yet)."""
    home = tmp_path / "ros_home"
    home.mkdir()
    return ros1_env(free_port(), home)


def _start_master(proc: subprocess.Popen[str], env: dict[str, str]) -> None:
    if not wait_until(lambda: master_answers(env["ROS_MASTER_URI"]) or proc.poll() is not None, 20):
        stop(proc)
        pytest.fail(f"master did not come up at {env['ROS_MASTER_URI']}")
    if proc.poll() is not None:
        _out, err = proc.communicate()
        pytest.fail(f"master exited early: {err.strip()}")


@pytest.fixture
def debian_master(ros_env: dict[str, str]) -> Iterator[dict[str, str]]:
    """Debian's real rosmaster (master + parameter server only, as roscore runs it)."""
    require_ros1_peers()
    port = ros_env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = debian_popen(["rosmaster", "--core", "-p", port], ros_env)
    _start_master(proc, ros_env)
    yield ros_env
    stop(proc)


@pytest.fixture
def debian_roscore(ros_env: dict[str, str]) -> Iterator[dict[str, str]]:
    """Debian's full roscore (master, /rosdistro and friends, rosout)."""
    require_ros1_peers()
    port = ros_env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = debian_popen(["roscore", "-p", port], ros_env)
    _start_master(proc, ros_env)
    from tests.support import debian

    wait_until(lambda: debian(["rosparam", "get", "/rosdistro"], ros_env).returncode == 0, 20)
    yield ros_env
    stop(proc, timeout=10)


@pytest.fixture
def rostool_master(ros_env: dict[str, str]) -> Iterator[dict[str, str]]:
    """rostool's own embedded master (`rostool core`)."""
    port = ros_env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = rostool_popen(["core", "--port", port], ros_env)
    _start_master(proc, ros_env)
    yield ros_env
    stop(proc)


@pytest.fixture(params=["debian_roscore", "rostool_master"])
def book_master(request: pytest.FixtureRequest) -> dict[str, str]:
    """The book's workflows run on Debian's roscore and on `rostool core` alike."""
    require_ros1_peers()
    env: dict[str, str] = request.getfixturevalue(request.param)
    return env
