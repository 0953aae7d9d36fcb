"""Shared helpers for tests: free ports, loopback ROS 1 environments, and Debian's real ROS 1 peers."""

from __future__ import annotations

import functools
import os
import random
import shutil
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TypeVar

import pytest

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")
DEBIAN_PYTHON = "/usr/bin/python3"
TESTDATA = Path(__file__).resolve().parent.parent.parent / "shared" / "testdata"


@functools.cache
def _ros1_peers_installed() -> bool:
    """Asked once per test process: the probe costs 0.2 s of CPU (1 s of wall under load), and ROS 1
    tests ask before every master they start."""
    if shutil.which("rosmaster") is None or not os.path.exists(DEBIAN_PYTHON):
        return False
    probe = subprocess.run(
        [DEBIAN_PYTHON, "-c", "import rospy, rostopic, rosparam, rosnode"],
        capture_output=True,
        env=debian_env({}),
    )
    return probe.returncode == 0


def require_ros1_peers() -> None:
    """Debian's ROS 1 tools must be here; in CI their absence fails the test, elsewhere it skips."""
    if not _ros1_peers_installed():
        message = "Debian's ROS 1 peers (ros-core, python3-rospy) are not installed: run ./test.sh as root"
        if IN_CI:
            pytest.fail(message)
        pytest.skip(message)


def xdist_worker() -> tuple[int, int]:
    """(index, count) of this pytest-xdist worker ("gw3" of 6 is (3, 6)); (0, 1) in a plain run."""
    name = os.environ.get("PYTEST_XDIST_WORKER", "")
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1") or 1)
    index = int(name[2:]) if name.startswith("gw") and name[2:].isdigit() else 0
    return index % max(count, 1), max(count, 1)


# TCP ports for the tests' servers (ROS 1 masters): below Linux's ephemeral range (32768-60999), so no
# OS-assigned port (an outgoing connection, a node's own server) can take one between free_port() and the
# server's bind; each xdist worker draws from its own slice, so workers never race for a port
SERVER_PORTS = range(20000, 32000)


def _tcp_port_free(port: int) -> bool:
    with socket.socket() as sock:  # no SO_REUSEADDR: a port still in TIME_WAIT counts as taken
        try:
            sock.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def free_port() -> int:
    """A free loopback TCP port of this worker's slice of SERVER_PORTS (random within it, so that separate
    pytest runs on one machine rarely meet; a port in use by anyone is skipped)."""
    index, count = xdist_worker()
    ports = SERVER_PORTS[index::count]
    for _ in range(200):
        port = random.choice(ports)
        if _tcp_port_free(port):
            return port
    raise RuntimeError(f"no free loopback port in {SERVER_PORTS} for xdist worker {index} of {count}")


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


# ROS 2 domains for the tests: Fast DDS and Cyclone put domain D's discovery ports at 7410 + 250 * D + 2 * p
# (participant p), which for 1..100 stays below the ephemeral range, so no OS-assigned UDP port takes one.
# Each xdist worker owns every count-th domain and cycles through them, so its domains are reused as late as
# possible and never by another worker of the run.
TEST_DOMAINS = range(1, 101)
_next_domain: list[int] = []


def _domain_in_use(domain: int, participants: int = 10) -> bool:
    """Whether a participant (a leftover peer, another pytest run) holds one of domain's first discovery
    ports: a leftover at a later index, once the first one has ended, would join the next test's graph
    (seen: a `/rostool_<pid>` node in a daemon's answer)."""
    for index in range(participants):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            try:
                sock.bind(("127.0.0.1", 7410 + 250 * domain + 2 * index))
            except OSError:
                return True
    return False


def fresh_domain() -> int:
    """The next ROS_DOMAIN_ID of this worker's share of TEST_DOMAINS that no participant uses now."""
    index, count = xdist_worker()
    domains = TEST_DOMAINS[index::count]
    if not _next_domain:
        _next_domain.append(random.randrange(len(domains)))  # separate runs start apart
    for _ in range(len(domains)):
        domain = domains[_next_domain[0] % len(domains)]
        _next_domain[0] += 1
        if not _domain_in_use(domain):
            return domain
    raise RuntimeError(f"every ROS 2 domain of xdist worker {index} of {count} is in use: {list(domains)}")


def ros2_env(**extra: str) -> dict[str, str]:
    """ROS 2 over DDS for one test: its own ROS_DOMAIN_ID, rostool's LOCALHOST discovery (127.0.0.1 only,
    multicast off), no inherited ROS settings."""
    from rostool.graph.ros2.dds import cyclone_config

    domain = fresh_domain()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS") and k != "CYCLONEDDS_URI"}
    env.update(
        ROS_VERSION="2",
        ROS_DOMAIN_ID=str(domain),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        PYTHONUNBUFFERED="1",
        # one test, one domain: a graph daemon per domain would outlive its test; the daemon's own tests
        # pass ROSTOOL_NO_DAEMON="" to use it
        ROSTOOL_NO_DAEMON="1",
        **extra,
    )
    assert "127.0.0.1" in cyclone_config(env)  # never anything but loopback
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


T = TypeVar("T")


def side_by_side(runs: Sequence[Callable[[], T]], workers: int = 3) -> list[T]:
    """Each run's result, in order, the runs done `workers` at a time: a test's independent rostool runs
    (none can show up in another's output) wait out their discovery together instead of one after the
    other. More fresh participants at once only make each one's discovery slower on two cores."""
    with ThreadPoolExecutor(max_workers=max(1, min(workers, len(runs)))) as pool:
        return list(pool.map(lambda run: run(), runs))


def master_answers(uri: str) -> bool:
    try:
        code, _msg, _pid = xmlrpc.client.ServerProxy(uri).getPid("/test")
        return bool(code == 1)
    except (OSError, xmlrpc.client.Error):
        return False


def master_names(uri: str) -> dict[str, set[str]]:
    """The ROS 1 master's graph at `uri` as getSystemState gives it (what rostopic/rosservice/rosnode list
    ask): {"topics": published or subscribed, "services": ..., "nodes": ...}; empty sets if it does not
    answer. Asked in process: a test waiting for a peer polls this instead of starting a tool per poll."""
    try:
        _code, _msg, (pubs, subs, srvs) = xmlrpc.client.ServerProxy(uri).getSystemState("/test")
    except (OSError, xmlrpc.client.Error, ValueError, TypeError):
        return {"topics": set(), "services": set(), "nodes": set()}
    entries = [*pubs, *subs, *srvs]
    return {
        "topics": {str(name) for name, _nodes in [*pubs, *subs]},
        "services": {str(name) for name, _nodes in srvs},
        "nodes": {str(node) for _name, nodes in entries for node in nodes},
    }


def master_has_node(uri: str, name: str) -> bool:
    """Whether node `name` is registered with the ROS 1 master at `uri` (XML-RPC lookupNode, as rosnode
    asks): its own XML-RPC server answers by then."""
    try:
        code, _msg, _uri = xmlrpc.client.ServerProxy(uri).lookupNode("/test", name)
        return bool(code == 1)
    except (OSError, xmlrpc.client.Error):
        return False


def master_has_param(uri: str, name: str) -> bool:
    """Whether the ROS 1 master at `uri` holds parameter `name` (XML-RPC getParam, as rosparam asks)."""
    try:
        code, _msg, _value = xmlrpc.client.ServerProxy(uri).getParam("/test", name)
        return bool(code == 1)
    except (OSError, xmlrpc.client.Error):
        return False


def rostool(
    args: Sequence[str],
    env: dict[str, str],
    timeout: float = 30,
    input: str | None = None,
    cwd: Path | None = None,
) -> subprocess.CompletedProcess[str]:
    """Run the installed rostool CLI as a user would."""
    return subprocess.run(
        [sys.executable, "-m", "rostool", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        input=input,
        cwd=cwd,
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


class Watched:
    """A running process whose output is collected as it comes, so a test waits for the lines it needs
    instead of sleeping: `watched = Watched(rostool_popen(...)); watched.wait_for(lambda out: ...)`."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self._out: list[str] = []
        self._err: list[str] = []
        self._changed = threading.Condition()
        self._readers = [
            threading.Thread(target=self._read, args=(proc.stdout, self._out), daemon=True),
            threading.Thread(target=self._read, args=(proc.stderr, self._err), daemon=True),
        ]
        for reader in self._readers:
            reader.start()

    def _read(self, stream: object, into: list[str]) -> None:
        for line in stream or ():  # type: ignore[attr-defined]
            with self._changed:
                into.append(line)
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    @property
    def stdout(self) -> str:
        with self._changed:
            return "".join(self._out)

    def wait_for(self, done: Callable[[str], bool], timeout: float = 20.0) -> bool:
        """Wait until `done(stdout so far)` holds (True), the process exits or `timeout` passes (False:
        the caller's assertion on the output then says what was missing)."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while not done("".join(self._out)):
                left = deadline - time.monotonic()
                if left <= 0 or (
                    self.proc.poll() is not None and not any(r.is_alive() for r in self._readers)
                ):
                    return done("".join(self._out))
                self._changed.wait(min(left, 0.2))
        return True

    def stop(self, timeout: float = 5.0) -> tuple[str, str]:
        """Interrupt it like Ctrl+C would (killed after `timeout`), then its whole stdout and stderr."""
        if self.proc.poll() is None:
            self.proc.send_signal(2)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for reader in self._readers:
            reader.join(timeout=5)
        with self._changed:
            return "".join(self._out), "".join(self._err)


# --- custom interfaces (.msg/.srv/.action) for Debian's peers: a source tree plus genpy classes ---------
PACKAGE_XML = """<?xml version="1.0"?>
<package format="2">
  <name>{name}</name>
  <version>0.0.1</version>
  <description>test package</description>
  <maintainer email="test@example.com">test</maintainer>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
</package>
"""

# Run with Debian's python3: writes genpy classes for every package of SRC into OUT, as catkin would.
# Dependencies' .msg texts come from Debian's installed classes; .action files expand as genaction does.
GENPY_SCRIPT = r"""
import os, sys
import genpy.generator, roslib.message
from genpy.generate_initpy import write_modules
out, src = sys.argv[1], sys.argv[2]
AUTOGEN = "# ====== DO NOT MODIFY! AUTOGENERATED FROM AN ACTION DEFINITION ======\n"
deps = os.path.join(out, "_msg_sources")
search = {}
for name in ["std_msgs/Header", "geometry_msgs/Point", "geometry_msgs/Quaternion", "geometry_msgs/Pose",
             "geometry_msgs/PoseStamped", "actionlib_msgs/GoalID", "actionlib_msgs/GoalStatus"]:
    pkg, typ = name.split("/")
    folder = os.path.join(deps, pkg)
    os.makedirs(folder, exist_ok=True)
    text = roslib.message.get_message_class(name)._full_text.split("\n" + "=" * 80 + "\n")[0]
    open(os.path.join(folder, typ + ".msg"), "w").write(text)
    search[pkg] = [folder]
packages = sorted(os.listdir(src))
for pkg in packages:
    generated = os.path.join(deps, "_" + pkg)
    os.makedirs(generated, exist_ok=True)
    search[pkg] = [os.path.join(src, pkg, "msg"), generated]
    action_dir = os.path.join(src, pkg, "action")
    for f in sorted(os.listdir(action_dir)) if os.path.isdir(action_dir) else []:
        name, pieces = f[:-len(".action")], [""]
        for line in open(os.path.join(action_dir, f)).read().split("\n"):
            if line.startswith("---"):
                pieces.append("")
            else:
                pieces[-1] += line + "\n"
        goal, result, feedback = pieces
        wrappers = {"Action": "%sActionGoal action_goal\n%sActionResult action_result\n"
                              "%sActionFeedback action_feedback" % (name, name, name),
                    "ActionGoal": "Header header\nactionlib_msgs/GoalID goal_id\n%sGoal goal" % name,
                    "ActionResult": "Header header\nactionlib_msgs/GoalStatus status\n%sResult result" % name,
                    "ActionFeedback": "Header header\nactionlib_msgs/GoalStatus status\n%sFeedback feedback"
                                      % name}
        texts = {"Goal": goal, "Result": result, "Feedback": feedback,
                 **{suffix: "\n" + body + "\n" for suffix, body in wrappers.items()}}
        for suffix, text in texts.items():
            open(os.path.join(generated, name + suffix + ".msg"), "w").write(AUTOGEN + text)
for pkg in packages:
    for kind, generator in (("msg", genpy.generator.MsgGenerator()), ("srv", genpy.generator.SrvGenerator())):
        folders = search[pkg] if kind == "msg" else [os.path.join(src, pkg, "srv")]
        files = [os.path.join(d, f) for d in folders if os.path.isdir(d)
                 for f in sorted(os.listdir(d)) if f.endswith("." + kind)]
        if files:
            target = os.path.join(out, pkg, kind)
            if generator.generate_messages(pkg, files, target, search):
                sys.exit("genpy failed for " + pkg)
            write_modules(target)
    open(os.path.join(out, pkg, "__init__.py"), "a").close()
"""


def interface_workspace(root: Path, files: dict[str, str]) -> Path:
    """A catkin source tree under root/src: `files` maps "pkg/srv/X.srv" to its text. Returns src."""
    src = root / "src"
    for relative, text in files.items():
        path = src / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        package = src / relative.split("/")[0]
        if not (package / "package.xml").exists():
            (package / "package.xml").write_text(PACKAGE_XML.format(name=package.name))
    return src


def with_genpy_classes(env: dict[str, str], src: Path, tmp_path: Path) -> dict[str, str]:
    """Generate Debian genpy classes for src; the returned env lets Debian's tools and rospy scripts
    import them (PYTHONUSERBASE survives debian_env) and rospack find the packages (ROS_PACKAGE_PATH)."""
    env = {**env, "PYTHONUSERBASE": str(tmp_path / "userbase"), "ROS_PACKAGE_PATH": str(src)}
    where = [DEBIAN_PYTHON, "-c", "import site; print(site.getusersitepackages())"]
    site = subprocess.run(where, env=debian_env(env), capture_output=True, text=True, check=True).stdout
    site = site.strip()
    done = subprocess.run([DEBIAN_PYTHON, "-c", GENPY_SCRIPT, site, str(src)], env=debian_env(env),
                          capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return env
