"""The real `ros2` (ros2cli Jazzy, installed by test.sh beside the Jazzy peers) as referee: a graph of real
rclpy nodes shared by a test module, and one case run as `ros2 ARGS` and `rostool --ros2 --ros2-backend B
ARGS` for B in dds and rclpy, each result recorded for docs/ros2cli-parity.md (tests/parity_table.py).

ros2 runs as a user's would: with its daemon (started and warmed up once per module, stopped at its end),
the loopback-only Fast DDS profile and the module's ROS_DOMAIN_ID. So does rostool: verbs that list the graph
are answered by its graph daemon of each backend (warmed up beside ros2's), echoes are relayed by it, and the
cases a module names `direct` are asked once more without it, so that the direct paths keep their referee
too. One `ros2` run is the referee of both backends. Verbs that list the graph run one after another (each
tool is a node that the others would see); a case that needs an event (`poke`) runs each tool alone; the
others run side by side. Waits for the daemons ask them in this process (`Ros2Daemon`, `daemon_answer`),
never by a `ros2` or `rostool` run per poll.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
import xmlrpc.client
from collections import Counter
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from tests.ros2_backends import rostool_lines
from tests.ros2_peers import (
    PEERS_DIR,
    RclpyPeer,
    WarmDaemon,
    assert_loopback_only,
    peer_env,
    rclpy_command,
    rostool_rclpy_popen,
)
from tests.support import IN_CI, ros2_env, wait_until

DISTRO = "jazzy"  # the distro of the referee's source
ROS2 = PEERS_DIR / DISTRO / "bin" / "ros2"
# where the results go (docs/ros2cli-parity.json to regenerate the docs); unset: nowhere, so that a test run
# leaves the checkout as it was
RESULTS = Path(os.environ["ROSTOOL_PARITY_RESULTS"]) if os.environ.get("ROSTOOL_PARITY_RESULTS") else None
BACKENDS = ("dds", "rclpy")

Normalize = Callable[[str], str]


def same_text(text: str) -> str:
    return text


def digits_zeroed(text: str) -> str:
    """Counters in the data, stamps and rates: every number's digits as 0."""
    return re.sub(r"\d+", "0", text)


def sorted_lines(text: str) -> str:
    """Line order where ros2 defines none (the ament index's file order)."""
    return "".join(sorted(text.splitlines(keepends=True)))


def without_observers(text: str) -> str:
    """The graph without the tools under test: a rostool run on the rclpy backend is a node (/rostool_PID)
    that ros2's daemon may still list for a moment after it ended; rostool's graph daemons are nodes that
    ros2 lists and that leave themselves out."""
    return "".join(line for line in text.splitlines(keepends=True) if not _OBSERVER.search(line))


_RUN_NODE = re.compile(r"\brostool_\d+\b")  # a rostool run on the rclpy backend, as a node
_OBSERVER = re.compile(_RUN_NODE.pattern + r"|^/_rostool_daemon_\d+$", re.MULTILINE)


def service_wait(text: str) -> str:
    """ros2 service call's waiting line, printed only when its new node has not yet discovered the server."""
    return text.replace("waiting for service to become available...\n", "")


def subscription_wait(text: str) -> str:
    """ros2 topic pub's waiting lines, one a second until discovery matched a subscription."""
    return "".join(
        line for line in text.splitlines(keepends=True) if not line.startswith("Waiting for at least")
    )


def goal_ids(text: str) -> str:
    return re.sub(r"ID: [0-9a-f]{32}", "ID: <uuid>", text)


def goal_accepted_first(text: str) -> str:
    """Goal ids as in `goal_ids`, and "Goal accepted" before the first feedback: ros2 prints it when its
    spin reaches the goal response, so feedback that arrived sooner is printed before it (an order ros2
    does not define); rostool prints it first, always."""
    text = goal_ids(text)
    accepted = "Goal accepted with ID: <uuid>\n\n"
    if accepted in text and "Feedback:\n" in text:
        text = text.replace(accepted, "", 1)
        first = text.index("Feedback:\n")
        text = text[:first] + accepted + text[first:]
    return text


def gids(text: str) -> str:
    return re.sub(r"GID: [0-9a-f.]+", "GID: <gid>", text)


@dataclass(frozen=True)
class Case:
    """One command line, both tools. `graph`: it lists the graph (run one tool at a time); `error`: ros2
    fails on it (same exit status, one line on rostool's stderr)."""

    verb: str
    flags: str
    args: tuple[str, ...]
    normalize: Normalize = same_text
    graph: bool = False
    error: bool = False
    timeout: float = 30.0
    name: str = ""  # how the results name it, when its arguments hold a temporary path
    # asked through rostool's daemon when it serves the verb (a listing, a subscription it relays), as users
    # run it (False: a count that would include the daemon)
    served: bool = True
    # rostool ARGS (DDS backend) run while each tool waits, for a case that needs an event to print on its
    # topic, its last argument (a parameter set for /parameter_events): see ParityGraph.poked
    poke: tuple[str, ...] = ()
    stdin: str | None = None

    @property
    def id(self) -> str:
        return self.name or " ".join(self.args)


@dataclass
class Run:
    code: int | None
    stdout: str
    stderr: str

    @property
    def stderr_lines(self) -> list[str]:
        return rostool_lines(self.stderr)


@dataclass
class Outcome:
    case: Case
    ros2: Run
    tools: dict[str, Run] = field(default_factory=dict)
    direct: dict[str, Run] = field(default_factory=dict)  # the same, without rostool's daemon


def require_ros2cli() -> None:
    if not ROS2.exists():
        message = f"the real ros2 (ros2cli Jazzy) is missing at {ROS2}: run ./test.sh"
        if IN_CI:
            pytest.fail(message)
        pytest.skip(message)


def _run(command: list[str], env: dict[str, str], timeout: float, stdin: str | None = None) -> Run:
    """A run to its end, or interrupted at `timeout` (SIGINT, then SIGKILL): what it printed until then is
    kept, so that a hang says where it hung."""
    process = subprocess.Popen(
        command, env=env, text=True, stdin=subprocess.PIPE if stdin is not None else subprocess.DEVNULL,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )  # fmt: skip
    try:
        out, err = process.communicate(stdin, timeout=timeout)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGINT)
        try:
            out, err = process.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            out, err = process.communicate()
        return Run(None, out, f"timed out after {timeout:g} s; then printed on SIGINT: {err}")
    return Run(process.returncode, out, err)


class Ros2Daemon:
    """ros2's daemon asked in this process, over the XML-RPC on which every `ros2` run asks it (127.0.0.1,
    port 11511 + ROS_DOMAIN_ID; ros2cli/daemon/__init__.py): a wait polls it without starting a `ros2`
    (0.35 s of CPU) per poll. None while it does not answer."""

    def __init__(self, env: dict[str, str]) -> None:
        self.url = f"http://127.0.0.1:{11511 + int(env['ROS_DOMAIN_ID'])}/ros2cli/"

    def ask(self, method: str, *args: object) -> Any:
        try:
            with xmlrpc.client.ServerProxy(self.url, allow_none=True) as proxy:
                return getattr(proxy, method)(*args)
        except (OSError, xmlrpc.client.Error):
            return None

    def nodes(self, hidden: bool = False) -> list[str] | None:
        """Full node names, as `ros2 node list` (`-a`: `hidden`) prints them."""
        found = self.ask("get_node_names_and_namespaces")
        if found is None:
            return None
        return [
            namespace.rstrip("/") + "/" + name
            for name, namespace in found
            if hidden or not name.startswith("_")
        ]

    def names(self, method: str) -> set[str]:
        """The names of a get_*_names_and_types answer (topics, services, actions)."""
        return {name for name, _types in self.ask(method) or []}


def daemon_answer(daemon: WarmDaemon, method: str, *args: object) -> Any:
    """rostool's graph daemon's answer to a Graph query (`node_names`: what `node list -a` through it
    prints), asked in this process through rostool's own client; None while it does not answer."""
    from rostool.errors import RostoolError
    from rostool.graph.daemon.client import DaemonAbsent, DaemonSilent, every_daemon

    try:
        (client,) = every_daemon(daemon.env)  # its runtime directory holds that one daemon
        return client.query(method, list(args))
    except (ValueError, DaemonAbsent, DaemonSilent, RostoolError):
        return None


# verbs whose subscription rostool's daemon relays (rostool/graph/daemon/relay_server.py): a run through it
# costs about half the CPU of one that joins the graph itself, and needs no discovery
RELAYED = {"topic echo"}


class ParityGraph:
    """The module's real nodes and the ways of asking them: ros2 (its daemon), rostool on each backend
    through its graph daemon (`served`) and without one."""

    def __init__(self, tmp: Path, peers: list[list[str]]) -> None:
        self.env = ros2_env()
        self.tmp = tmp
        self.peer_env = peer_env(self.env, tmp)
        venv = str(PEERS_DIR / DISTRO)
        self.ros2_env = dict(
            self.peer_env, AMENT_PREFIX_PATH=venv, PATH=f"{venv}/bin:{self.peer_env['PATH']}"
        )
        self.peers = [RclpyPeer(DISTRO, self.env, tmp, args) for args in peers]
        self.daemons: dict[str, WarmDaemon] = {}
        self.ros2_daemon = Ros2Daemon(self.env)
        self.outcomes: list[Outcome] = []
        # the nodes ros2's daemon lists when no case runs: the peers and the daemons (set by warm_up)
        self.at_rest: Counter[str] = Counter()

    def ros2(self, args: list[str], timeout: float = 30, stdin: str | None = None) -> Run:
        return _run(self.ros2_command(args), self.ros2_env, timeout, stdin)

    def ros2_steady(self, args: list[str], timeout: float = 30, stdin: str | None = None) -> Run:
        """ros2, asked again (up to twice) when it crashed on a node that left between its daemon's node
        list and a question about that node (rclpy's "RCLError ... error not set", as after a rostool run on
        the rclpy backend ends), once its daemon no longer lists such a run: the referee's own flake, not an
        answer to judge."""
        for _again in range(2):
            run = self.ros2(args, timeout, stdin)
            if not ("Traceback" in run.stderr and "RCLError" in run.stderr):
                return run
            self.no_run_left()
        return self.ros2(args, timeout, stdin)

    def listed(self) -> Counter[str] | None:
        """The nodes ros2's daemon lists (hidden ones too), each daemon's under one name whatever its id."""
        nodes = self.ros2_daemon.nodes(hidden=True)
        return None if nodes is None else Counter(_DAEMON_ID.sub(r"\1", node) for node in nodes)

    def settle(self) -> None:
        """Wait until ros2's daemon lists exactly the graph at rest (`at_rest`), before a case that counts
        every node: an earlier case's runs gone from its view (a rostool run on the rclpy backend is a node
        for ~0.5 s after it ends; a run interrupted at its timeout, or killed, stays until its lease ends).
        Still not at rest after 25 s (past Fast DDS's 20 s lease), ros2's daemon lists a node that left for
        good (ros2/ros2#514, seen in CI: 7 nodes where 6 ran, three tries in a row): restarted, its documented
        cure, and asked again; the case then fails if it still counts one too many."""
        if wait_until(lambda: self.listed() == self.at_rest, 25):
            return
        print(f"ros2's daemon lists {self.listed()}, at rest {self.at_rest}", file=sys.stderr)
        self.ros2(["daemon", "stop"])
        self.ros2(["daemon", "start"])
        if not wait_until(lambda: self.listed() == self.at_rest, 30):
            print(f"restarted, ros2's daemon lists {self.listed()}", file=sys.stderr)

    def no_run_left(self) -> None:
        """Wait (up to 5 s) until ros2's daemon no longer lists a rostool run on the rclpy backend (a node
        while it runs, gone ~0.5 s after it ended)."""

        def gone() -> bool:
            nodes = self.ros2_daemon.nodes(hidden=True)
            return nodes is not None and not any(_RUN_NODE.search(node) for node in nodes)

        wait_until(gone, 5)

    def ros2_command(self, args: list[str]) -> list[str]:
        return [str(ROS2), *args]

    def rostool(
        self,
        backend: str,
        args: list[str],
        timeout: float = 30,
        stdin: str | None = None,
        served: bool = False,
    ) -> Run:
        command, env = self.rostool_command(backend, args, served)
        return _run(command, env, timeout, stdin)

    def rostool_command(
        self, backend: str, args: list[str], served: bool = False
    ) -> tuple[list[str], dict[str, str]]:
        env = self.daemons[backend].env if served else self.env
        if backend == "rclpy":
            return rclpy_command(["--ros2", *args], DISTRO), peer_env(env, self.tmp)
        return [sys.executable, "-m", "rostool", "--ros2", *args], env

    def compare(self, case: Case, direct: bool = False) -> Outcome:
        """ros2 and rostool on both backends; a listing through rostool's daemons, and with `direct` also
        without them (`Outcome.direct`)."""
        # the rclpy backend before the DDS one: its node has left ros2's view by the next case
        order = ("rclpy", "dds")
        served = case.served and (case.graph or case.verb in RELAYED)
        jobs: list[Callable[[], Run]] = [lambda: self.ros2_steady(list(case.args), case.timeout, case.stdin)]
        jobs += [
            lambda b=b: self.rostool(b, list(case.args), case.timeout, case.stdin, served) for b in order
        ]
        if direct:
            jobs += [lambda b=b: self.rostool(b, list(case.args), case.timeout, case.stdin) for b in order]
        if case.graph and not case.served:
            # a count of every node: each tool counts the graph at rest
            runs = [(self.settle(), job())[1] for job in jobs]
        elif case.graph:
            runs = [job() for job in jobs]
        elif case.poke:
            runs = [self.poked(job, case) for job in jobs]
        else:
            with ThreadPoolExecutor(len(jobs)) as pool:
                runs = list(pool.map(lambda job: job(), jobs))
        outcome = Outcome(case, runs[0], dict(zip(order, runs[1:3], strict=True)))
        if direct:
            outcome.direct = dict(zip(order, runs[3:], strict=True))
        self.outcomes.append(outcome)
        return outcome

    def poked(self, job: Callable[[], Run], case: Case) -> Run:
        """One tool's run of a case that needs an event, alone, while rostool's DDS backend runs `case.poke`:
        once ros2's daemon counts one more subscription of the topic than before (at most 3 s), then every
        second. Alone and poked by no rclpy node, since every new rclpy node (a `ros2` run, a rostool run
        on the rclpy backend) publishes a ParameterEvent of its own as it starts (use_sim_time declared),
        which an echo already subscribed took first under load (2 runs in 15 beside two busy loops)."""
        topic = case.args[-1]
        before = self.ros2_daemon.ask("count_subscribers", topic) or 0
        done = threading.Event()

        def poke() -> None:
            wait_until(
                lambda: done.is_set() or (self.ros2_daemon.ask("count_subscribers", topic) or 0) > before, 3
            )
            while not done.is_set():
                self.rostool("dds", list(case.poke))
                done.wait(1.0)

        with ThreadPoolExecutor(1) as pool:
            pool.submit(poke)
            try:
                return job()
            finally:
                done.set()

    def warm_up(self, ready: Callable[[ParityGraph], bool]) -> None:
        """Start ros2's daemon and rostool's (one per backend) and wait until each has seen the whole graph
        (a fresh daemon answers with what it has discovered so far)."""
        self.daemons = {
            "dds": WarmDaemon(self.env),
            "rclpy": WarmDaemon(self.env, lambda args, env: rostool_rclpy_popen(args, env, self.tmp, DISTRO)),
        }
        for peer in self.peers:
            peer.wait_for("ready", timeout=30)
        self.ros2(["daemon", "start"])
        for daemon in self.daemons.values():
            daemon.ready()
        # asked in this process: a `ros2` or `rostool` run per poll cost 0.1-0.4 s of CPU each
        assert wait_until(lambda: ready(self), timeout=30), "ros2's daemon never saw the graph"
        whole = self.ros2_daemon.nodes(hidden=True) or []
        peers = Counter(name for name in whole if not _DAEMONS.search(name))  # twins count twice
        for backend, daemon in self.daemons.items():

            def seen(daemon: WarmDaemon = daemon) -> bool:
                return peers <= Counter(daemon_answer(daemon, "node_names") or [])

            assert wait_until(seen, timeout=30), f"rostool's {backend} daemon never saw the graph"
        self.at_rest = peers + Counter({"/_ros2cli_daemon": 1, "/_rostool_daemon": len(self.daemons)})
        wait_until(lambda: self.listed() == self.at_rest, 10)  # rostool's daemons in ros2's view too

    def close(self) -> None:
        self.ros2(["daemon", "stop"])
        left = [pid for daemon in self.daemons.values() for pid in daemon.stop()]
        for peer in self.peers:
            addresses = peer.bound_addresses()
            peer.stop()
            assert_loopback_only(addresses)
        assert not left, f"graph daemons still running after `daemon stop --all`: {left}"


# the daemons' own nodes: ros2's and rostool's
_DAEMONS = re.compile(r"^/_ros2cli_daemon|^/_rostool_daemon|\brostool_\d+\b")
# a daemon's node name without its ids: /_ros2cli_daemon_<domain>_<uuid>, /_rostool_daemon_<pid>
_DAEMON_ID = re.compile(r"^(/_ros2cli_daemon|/_rostool_daemon)_.*")


@contextlib.contextmanager
def parity_graph(
    tmp: Path, peers: list[list[str]], ready: Callable[[ParityGraph], bool]
) -> Iterator[ParityGraph]:
    """A module's graph: its peers up and ros2's daemon warmed up; at the end, the daemon stopped, the peers
    checked for loopback-only sockets, and the judged cases recorded."""
    require_ros2cli()
    graph = ParityGraph(tmp, peers)
    try:
        graph.warm_up(ready)
        yield graph
    finally:
        graph.close()
        record()


# --- results ------------------------------------------------------------------------------------------
SAME, DIFFERS, MISSING, ONLY_ROSTOOL = "same", "differs", "missing in rostool", "only in rostool"


def record() -> None:
    """Merge the judged cases into RESULTS (keyed by command line and backend)."""
    if not RESULT_ROWS or RESULTS is None:
        return
    existing: dict[str, dict[str, str]] = {}
    if RESULTS.exists():
        existing = {f"{r['args']}|{r['backend']}": r for r in json.loads(RESULTS.read_text())["results"]}
    existing.update({f"{args}|{backend}": row for (args, backend), row in RESULT_ROWS.items()})
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    rows = sorted(existing.values(), key=lambda r: (r["verb"], r["flags"], r["args"], r["backend"]))
    RESULTS.write_text(json.dumps({"referee": f"ros2cli {DISTRO}", "results": rows}, indent=1) + "\n")


RESULT_ROWS: dict[tuple[str, str], dict[str, str]] = {}


def judge(case: Case, backend: str, result: str, why: str = "") -> None:
    RESULT_ROWS[(case.id, backend)] = {
        "verb": case.verb, "flags": case.flags, "args": case.id, "backend": backend, "result": result,
        "why": why,
    }  # fmt: skip


def wait_ros2(
    graph: ParityGraph,
    args: list[str],
    expected: str,
    timeout: float = 20,
    gate: Callable[[], bool] | None = None,
) -> bool:
    """Until `ros2 ARGS` prints `expected`; `gate`: a check in this process (ros2's daemon asked directly)
    that must pass before each run, so that ros2 runs only once what it waits for is likely there."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if gate is not None and not gate():
            time.sleep(0.05)
            continue
        if expected in graph.ros2(args).stdout:
            return True
    return False
