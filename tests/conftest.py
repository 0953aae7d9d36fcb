"""Fixtures: each test gets its own master on a free loopback port. Scheduling under pytest-xdist: the
longest tests first, and tests marked `alone` (they measure rates or time windows) while no other runs."""

from __future__ import annotations

import fcntl
import os
import signal
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import (
    debian_popen,
    free_port,
    master_answers,
    master_has_param,
    require_ros1_peers,
    ros1_env,
    rostool_popen,
    stop,
    wait_until,
)

# Tests end peers and rostool as Ctrl+C does (SIGINT). A suite started in the background by a
# non-interactive shell (`./test.sh &`, CI runners' scripts) inherits SIGINT ignored, and so would every
# process it starts: a peer would never see the signal. A handler set here is reset to the default in
# children at exec.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# rostool follows ROS 2's default discovery range (SUBNET: multicast on the host's interfaces). A test whose
# environment is a copy of this one, not ros2_env()'s, must still stay on loopback (the network rule): the
# suite's own processes default to LOCALHOST. Across-machines tests run in private namespaces with the
# user's defaults (tests/netns.py) and remove the variable themselves.
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

# the real ROS 2 peers' fixtures (distro, graph_env, start_peer)
pytest_plugins = ("tests.ros2_peers", "tests.ros2_backends", "tests.netns")

# Modules whose tests each take half a minute or more (dozens of rostool runs against one graph): started
# first, so that no xdist worker begins one of them when the others are nearly done
LONG_MODULES = {
    "test_ros2cli_forms",
    "test_ros2cli_forms_param",
    "test_ros2cli_forms_service_action",
    "test_ros2cli_parity",
    "test_ros2_fastdds_rpc",
    "test_ros2_real_bad_input",
    "test_bad_input_live",
    "test_lifecycle",
    "test_daemon",
    "test_console",
    "test_across_machines",
}


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "alone: measures a rate or a time window: runs while no other test of the session runs"
    )
    from tests.cpu_profile import register

    register(config)  # ROSTOOL_TEST_CPU=DIR: CPU seconds per test (tests/cpu_profile.py)


# why each rerun test failed (its last lines): `-r R` names the reruns, and a rerun is a flake to fix
RERUN_WHY: list[tuple[str, str]] = []
RERUN_LINES = 15


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.outcome == "rerun":  # pytest-rerunfailures' outcome; under xdist, reported in the controller
        lines = report.longreprtext.splitlines()
        errors = [line for line in lines if line.startswith("E ")][:RERUN_LINES] + lines[-1:]  # + where
        RERUN_WHY.append((report.nodeid, "\n".join(errors if len(errors) > 1 else lines[-RERUN_LINES:])))


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if RERUN_WHY:
        terminalreporter.section("why tests were rerun")
        for nodeid, why in RERUN_WHY:
            terminalreporter.write_line(f"{nodeid}:\n{why}\n")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Long modules first, `alone` tests last (they stop the other workers while they run); otherwise the
    order of the files. Every xdist worker sorts alike, so their collections stay identical."""

    def rank(item: pytest.Item) -> int:
        if item.get_closest_marker("alone"):
            return 2
        return 0 if item.path.stem in LONG_MODULES else 1

    items.sort(key=rank)


@pytest.fixture(autouse=True)
def _alone_when_marked(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[None]:
    """Under xdist, a test marked `alone` holds the session's gate exclusively, every other test shares it.
    `alone` tests are collected last, so they are handed out when nothing else is left to start: no
    turnstile, the other workers finish what they hold (and the waiting costs no idle worker)."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        yield
        return
    session_dir = tmp_path_factory.getbasetemp().parent  # shared by the workers of one session
    alone = request.node.get_closest_marker("alone") is not None
    with open(session_dir / "alone.lock", "a") as gate:
        fcntl.flock(gate, fcntl.LOCK_EX if alone else fcntl.LOCK_SH)
        try:
            yield
        finally:
            fcntl.flock(gate, fcntl.LOCK_UN)


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
    # roslaunch sets /rosdistro once the master answers; asked as `rosparam get` asks (getParam), in
    # process: a rosparam run per poll cost 0.2-0.3 s of CPU each
    wait_until(lambda: master_has_param(ros_env["ROS_MASTER_URI"], "/rosdistro"), 20)
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
