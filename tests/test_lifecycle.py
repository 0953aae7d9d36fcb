"""lifecycle nodes/get/list/set against real rclpy LifecycleNodes (tests/lifecycle_peer.py), on both ROS 2
backends, compared byte for byte (stdout, exit status, stderr's own lines) with the real `ros2 lifecycle`
(ros2cli Jazzy); `set` must really move the node (the node reports its state machine's new state)."""

from __future__ import annotations

import os
import subprocess
import time
import xmlrpc.client
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests import ros2_peers
from tests.ros2_backends import ServedTool, Tool, rostool_lines
from tests.ros2_peers import PEERS_DIR, StartPeer, assert_loopback_only, bound_addresses, peer_env
from tests.support import IN_CI, wait_until

HERE = Path(__file__).resolve().parent
ROS2CLI_VENV = PEERS_DIR / "jazzy"
NODE, HIDDEN = "/test_lifecycle_node", "/_hidden_test_lifecycle_node"


@pytest.fixture
def start_script(monkeypatch: pytest.MonkeyPatch, start_peer: StartPeer) -> StartPeer:
    """start_peer's real rclpy nodes (same venv, loopback-only environment, JSON events, teardown checks),
    running tests/lifecycle_peer.py."""
    monkeypatch.setattr(ros2_peers, "PEER_SCRIPT", HERE / "lifecycle_peer.py")
    return start_peer


Ros2 = Callable[[list[str]], "subprocess.CompletedProcess[str]"]


@pytest.fixture
def ros2(graph_env: dict[str, str], tmp_path: Path) -> Iterator[Ros2]:
    """ros2(args): the real `ros2` (ros2cli Jazzy) in the test's graph, through its daemon (as ros2cli's own
    tests run it: a direct call's fixed 0.5 s spin often ends before Fast DDS discovered the nodes). The
    daemon serves XML-RPC on 127.0.0.1 and runs DDS with the peers' loopback-only profile; it is stopped at
    the end."""
    if not (ROS2CLI_VENV / ".ros2cli").exists():
        message = f"the real ros2 CLI is missing in {ROS2CLI_VENV}: run ./test.sh"
        if IN_CI:
            pytest.fail(message)
        pytest.skip(message)
    env = peer_env(graph_env, tmp_path)
    env["AMENT_PREFIX_PATH"] = str(ROS2CLI_VENV)

    def run(args: list[str]) -> subprocess.CompletedProcess[str]:
        command = [str(ROS2CLI_VENV / "bin" / "ros2"), *args]
        return subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)

    run(["daemon", "start"])
    yield run
    daemons = [
        pid for pid in os.listdir("/proc") if pid.isdigit() and _is_daemon_of(pid, env["ROS_DOMAIN_ID"])
    ]
    addresses = [address for pid in daemons for address in bound_addresses(int(pid))]
    run(["daemon", "stop"])
    assert daemons, "the real ros2 daemon was not running"
    assert_loopback_only(addresses)


def _is_daemon_of(pid: str, domain: str) -> bool:
    try:
        words = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:  # gone meanwhile
        return False
    flag = b"--ros-domain-id"
    return b"ros2-daemon" in words and flag in words[:-1] and words[words.index(flag) + 1] == domain.encode()


def ros2_sees(env: dict[str, str], nodes: list[str]) -> None:
    """Wait until the referee's daemon has discovered every node of `nodes` (lifecycle services too): the
    nodes `ros2 lifecycle nodes -a` would list (ros2lifecycle's rule: a node serving `<node>/get_state` of
    lifecycle_msgs/srv/GetState), asked on the daemon's XML-RPC (127.0.0.1, port 11511 + domain) from this
    process, as each `ros2` run asks it (a `ros2` run per poll cost 0.5 s of CPU)."""
    daemon = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{11511 + int(env['ROS_DOMAIN_ID'])}/ros2cli/")

    def lifecycle_nodes() -> list[str]:
        served = {name for name, types in daemon.get_service_names_and_types()
                  if "lifecycle_msgs/srv/GetState" in types}  # fmt: skip
        full = (
            namespace.rstrip("/") + "/" + name for name, namespace in daemon.get_node_names_and_namespaces()
        )
        return sorted(node for node in full if f"{node}/get_state" in served)

    deadline = time.monotonic() + 20
    while (listed := lifecycle_nodes()) != sorted(nodes):
        assert time.monotonic() < deadline, f"the real ros2 sees {listed}, not {nodes}"
        time.sleep(0.2)


def same_as_ros2(tool: Tool, ros2: Ros2, args: list[str], attempts: int = 1) -> None:
    same_as(tool, ros2(args), args, attempts)


def same_as(tool: Tool, theirs: subprocess.CompletedProcess[str], args: list[str], attempts: int = 1) -> None:
    """rostool's run of `args` prints what the real ros2's run printed (`theirs`)."""
    for attempt in range(attempts):
        ours = tool(args)
        if (ours.stdout, ours.returncode) == (theirs.stdout, theirs.returncode) or attempt == attempts - 1:
            break
    assert (ours.stdout, ours.returncode) == (theirs.stdout, theirs.returncode), (args, ours.stderr)
    assert ours.stderr_lines == rostool_lines(theirs.stderr), args  # type: ignore[attr-defined]


# whole-graph forms: a new rclpy participant may meet a Fast DDS peer only at the peer's next periodic
# announcement (every 3 s), after the rclpy backend's graph already looked settled; they get 3 tries there
LISTING_FORMS = [["nodes"], ["nodes", "-a"], ["nodes", "-c"], ["nodes", "-a", "-c"], ["get"]]
NAMED_FORMS = [
    ["get", NODE],
    ["get", "--include-hidden-nodes", HIDDEN],
    ["get", HIDDEN],
    ["get", "/nonexistent_test_lifecycle_node"],
    ["list", "test_lifecycle_node"],
    ["list", "--include-hidden-nodes", HIDDEN, "-a"],
    ["list", HIDDEN, "-a"],
]
# each asks for a transition (refused: none may move a node), so one after the other, after the reads
SET_FORMS = [
    ["set", NODE, "noop"],
    ["set", "/nonexistent_test_lifecycle_node", "configure"],
    ["set", HIDDEN, "configure"],
]


@pytest.mark.parametrize("distro", ["jazzy"])
def test_lifecycle_forms_print_what_ros2_prints(
    served_tool: ServedTool, ros2: Ros2, start_script: StartPeer, backend: str, graph_env: dict[str, str]
) -> None:
    """ros2lifecycle's own test cases (its test/test_cli.py), run by both tools on the same nodes, each
    through its daemon (rostool's direct forms: test_set_moves_the_node_through_its_states). The reads run
    side by side (a rostool on rclpy is a node, but no lifecycle node: no form lists it; a lifecycle
    service's requests are empty, so while no node moves all its replies are the same, and one that
    rostool's DDS client of the Fast DDS node takes from another caller prints alike: services.py)."""
    tool = served_tool
    start_script.together([], ["--name", HIDDEN[1:]])  # the two nodes start side by side
    ros2_sees(graph_env, [NODE, HIDDEN])
    tool.daemon.ready()
    # the two lifecycle nodes and the real ros2's own daemon node
    assert wait_until(lambda: tool.daemon.graph_size()["nodes"] == 3, timeout=20)
    attempts = 3 if backend == "rclpy" else 1
    # the real ros2's reads first, then rostool's: each `ros2` run is a new participant (its node calls the
    # services), and rostool's daemon lets a newcomer describe itself (up to 1 s) before it answers a query,
    # one query at a time; a rostool read beside a few of them could wait past the 3 s after which the verb
    # answers directly and says so on stderr
    forms = [(["lifecycle", *args], attempts) for args in LISTING_FORMS]
    forms += [(["lifecycle", *args], 1) for args in NAMED_FORMS]
    with ThreadPoolExecutor(max_workers=4) as pool:
        theirs = list(pool.map(ros2, [args for args, _attempts in forms]))
    with ThreadPoolExecutor(max_workers=4) as pool:
        listed_run = pool.submit(tool, ["lifecycle", "list", NODE])
        compared = [pool.submit(same_as, tool, their, args, tries)
                    for (args, tries), their in zip(forms, theirs, strict=True)]  # fmt: skip
    for done in compared:
        done.result()
    for args in SET_FORMS:
        same_as_ros2(tool, ros2, ["lifecycle", *args])
    listed = listed_run.result().stdout
    assert listed == "- configure [1]\n\tStart: unconfigured\n\tGoal: configuring\n" + (
        "- shutdown [5]\n\tStart: unconfigured\n\tGoal: shuttingdown\n"
    )


def test_set_moves_the_node_through_its_states(
    tool: Tool, ros2: Ros2, start_script: StartPeer, graph_env: dict[str, str]
) -> None:
    """set moves the real node; nodes, list, get and set asked directly (no daemon) on both backends. The
    sets one after the other; the reads between two sets side by side."""
    peer = start_script()
    ros2_sees(graph_env, [NODE])
    with ThreadPoolExecutor() as pool:
        for done in [pool.submit(same_as_ros2, tool, ros2, ["lifecycle", *args], 3)
                     for args in (["nodes"], ["list", NODE])]:  # fmt: skip
            done.result()
    steps = [("configure", "inactive [2]"), ("3", "active [3]"), ("deactivate", "inactive [2]"),
             ("cleanup", "unconfigured [1]")]  # fmt: skip
    for number, (transition, state) in enumerate(steps, start=1):
        done = tool(["lifecycle", "set", NODE, transition])
        assert (done.stdout, done.returncode) == ("Transitioning successful\n", 0), done.stderr
        peer.wait_for("state", lambda _e, n=number: len(peer.of("state")) >= n)
        assert peer.of("state")[-1]["label"] == state.split()[0]
        with ThreadPoolExecutor() as pool:
            theirs, ours = pool.map(lambda run: run(["lifecycle", "get", NODE]), (ros2, tool))
        assert theirs.stdout == state + "\n"
        assert ours.stdout == state + "\n"


def test_lifecycle_needs_a_ros2_graph() -> None:
    from tests.support import rostool

    done = rostool(["--ros1", "lifecycle", "nodes"], {"ROS_MASTER_URI": "http://127.0.0.1:9", "PATH": "/bin"})
    assert done.returncode != 0
    assert done.stderr.strip().splitlines() == [
        "rostool: lifecycle is a ROS 2 feature; select a ROS 2 graph with --ros2 (or ROS_VERSION=2)"
    ]
