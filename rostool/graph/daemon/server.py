"""The daemon process: one long-lived graph of the selected backend, its read-only queries served on a
Unix-domain socket (0600, in the user's 0700 directory); no TCP or UDP port of its own. It also relays
subscriptions (relay_server.py): a verb's reader in this graph, its messages streamed to the verb; and
makes service calls for verbs (call_server.py: parameters, `service call`, lifecycle, logger levels) and
sends their goals (goal_server.py: `action send-goal`).

Life: take the key's lock (held until exit: a second daemon of the same key waits or gives up), open the
graph and let discovery settle, then bind the socket; clients meanwhile find the lock held and answer
directly. It exits after `--idle` seconds without a request, on `daemon stop`, on SIGTERM, and when a
client of another build asks (that client starts the replacement), removing its socket.
"""

from __future__ import annotations

import argparse
import contextlib
import fcntl
import logging
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from rostool.errors import RostoolError
from rostool.graph.daemon import wire
from rostool.graph.daemon.call_server import Calls
from rostool.graph.daemon.goal_server import GoalRun
from rostool.graph.daemon.memory import memory
from rostool.graph.daemon.place import DaemonPlace, build_id, daemon_place
from rostool.graph.daemon.queries import SERVED
from rostool.graph.daemon.relay_server import Relay, qos_of

DEFAULT_IDLE_SECONDS = 7200.0  # `daemon start`: as ros2 daemon's default timeout
# A daemon a verb started by itself: a user who moves between domains, backends or environments starts
# one per key, and two hours of each piled up (11 daemons of 34-60 MB after an hour of checks).
AUTO_IDLE_SECONDS = 900.0
IDLE_ENV = "ROSTOOL_DAEMON_IDLE"
LOCK_WAIT_SECONDS = 10.0  # a replaced daemon's time to go
CLIENT_SECONDS = 5.0  # how long one client may take to send its request or read the answer
MAX_CLIENTS = 256
CALL_OPS = ("call_open", "call_wait", "call")  # call_server.py's
MAX_RELAYS = 128  # subscriptions relayed at once; past it a client subscribes itself
NODE_NAME = "_rostool_daemon"  # hidden (a leading `_`), as ros2cli's own daemon node
log = logging.getLogger("rostool.daemon")


class Daemon:
    def __init__(self, place: DaemonPlace, requested: str, idle: float, auto: bool = False) -> None:
        self.place = place
        self.requested = requested
        self.idle = idle
        self.auto = auto  # started by a verb, not by `daemon start`
        self.build = build_id()
        self.started = time.monotonic()
        self.last_request = self.started
        self.quiet_for = 0.0  # how long it had been idle when the latest request came (status says it)
        self.stopping = threading.Event()
        self.graph_lock = threading.Lock()
        self.clients = threading.BoundedSemaphore(MAX_CLIENTS)
        self.backend = ""
        self.graph: Any = None
        self.calls: Calls | None = None
        self.relays: set[Relay] = set()
        self.relays_lock = threading.Lock()
        self.goals: set[GoalRun] = set()  # goals sent for verbs, running (under relays_lock)
        self.queries = 0  # graph queries answered (`daemon status` shows whether calls reach this daemon)

    # --- the graph -------------------------------------------------------------------------------
    def open_graph(self) -> None:
        from rostool.graph.backends import open_ros2

        self.backend, self.graph = open_ros2(None if self.requested == "auto" else self.requested, NODE_NAME)
        self.graph.require_peers = False  # an empty graph is an empty answer, as ros2's daemon gives
        self.graph.wait_for_discovery()
        self.calls = Calls(self.graph, self.graph_lock)
        log.info("graph of %s (%s backend) ready", dict(self.place.fields)["domain"], self.backend)

    def answer(self, request: dict[str, Any]) -> dict[str, Any]:
        op = request.get("op")
        if op == "status":
            return {"ok": self.status()}
        if op == "stop":
            self.stopping.set()
            return {"ok": True}
        if op not in ("query", *CALL_OPS):
            return {"error": f"graph daemon: unknown request {op!r}"}
        other = self._other_build(request)
        if other is not None:
            return other
        if op in CALL_OPS and self.calls is not None:  # a call made for the verb: not under the lock
            self.queries += 1
            return self.calls.answer(request)
        method, args = request.get("method"), request.get("args", [])
        if method == "type_distro":  # the distro the client decodes relayed messages with
            return {"ok": self.graph.types.distro}
        served = SERVED.get(str(method))
        if served is None or not isinstance(args, list):
            return {"error": f"graph daemon: {method!r} is not a query it answers"}
        try:
            with self.graph_lock:
                self.queries += 1
                self.graph.wait_for_newcomers(ignore=_guid(request.get("own")))
                return {"ok": served[0](getattr(self.graph, str(method))(*args))}
        except RostoolError as err:
            return {"error": str(err)}

    def _other_build(self, request: dict[str, Any]) -> dict[str, Any] | None:
        if request.get("build") == self.build:
            return None
        log.info("a client of build %s asked: this daemon (%s) stops", request.get("build"), self.build)
        self.stopping.set()
        return {"build": self.build}

    def relay(self, connection: socket.socket, request: dict[str, Any]) -> None:
        """Serve a "subscribe" request: answer, then stream the topic's messages until the client goes."""
        reply = self._other_build(request)
        topic = request.get("topic")
        if reply is None and not isinstance(topic, str):
            reply = {"error": "graph daemon: a subscription names its topic"}
        with self.relays_lock:
            full = len(self.relays) >= MAX_RELAYS
        if reply is None and full:
            reply = {"direct": f"the graph daemon relays {MAX_RELAYS} subscriptions already"}
        relay = None
        if reply is None:
            relay = Relay(self.graph, self.graph_lock, connection, str(topic))
            try:
                relay.open(qos_of(request.get("qos", {})))
                reply = {"ok": True}
            except RostoolError as err:
                reply, relay = {"error": str(err)}, None
        wire.send(connection, reply)
        if relay is None:
            return
        with self.relays_lock:
            self.relays.add(relay)
        log.info("relaying %s (%d relays)", topic, len(self.relays))
        try:
            relay.run()
        finally:
            with self.relays_lock:
                self.relays.discard(relay)
            log.info("relay of %s closed", topic)

    def goal(self, connection: socket.socket, request: dict[str, Any]) -> None:
        """Serve a "goal" request: answer, then send the goal and stream its run until it ends."""
        other = self._other_build(request)
        if other is not None:
            wire.send(connection, other)
            return
        self.queries += 1
        run = GoalRun(self.graph, self.graph_lock, connection, self.backend)
        with self.relays_lock:
            self.goals.add(run)
        try:
            run.serve(request)
        finally:
            with self.relays_lock:
                self.goals.discard(run)

    def status(self) -> dict[str, Any]:
        with self.graph_lock:
            size = {
                "nodes": len(self.graph.node_names()),
                "topics": len(self.graph.topics()),
                "services": len(self.graph.services()),
                "actions": len(self.graph.actions()),
            }
        uptime = round(time.monotonic() - self.started, 3)
        return {
            "running": True, "pid": os.getpid(), "socket": str(self.place.socket), "backend": self.backend,
            "domain": int(dict(self.place.fields)["domain"]), "uptime": uptime,
            "build": self.build, "log": str(self.place.log), "graph": size, "key": dict(self.place.fields),
            "relays": sorted(relay.topic for relay in list(self.relays)), "memory": memory(),
            "queries": self.queries, "idle_exit": self.idle, "auto_started": self.auto,
            "idle": round(self.quiet_for, 3),
        }  # fmt: skip

    # --- the socket ------------------------------------------------------------------------------
    def serve(self) -> None:
        listener = bind(self.place.socket)
        identity = os.stat(self.place.socket).st_ino
        log.info("listening on %s", self.place.socket)
        threading.Thread(target=self._keep_current, name="poll", daemon=True).start()
        try:
            while not self.stopping.is_set():
                if not self.relays and not self.goals and time.monotonic() - self.last_request > self.idle:
                    log.info("idle for %g s: exiting", self.idle)
                    break
                try:
                    connection, _ = listener.accept()
                except TimeoutError:
                    continue
                except OSError:
                    if self.stopping.is_set():
                        break
                    raise
                now = time.monotonic()
                self.quiet_for, self.last_request = now - self.last_request, now
                if not self.clients.acquire(blocking=False):
                    connection.close()
                    continue
                threading.Thread(target=self._client, args=(connection,), daemon=True).start()
        finally:
            listener.close()
            with contextlib.suppress(OSError):
                if os.stat(self.place.socket).st_ino == identity:  # not a successor's socket
                    os.unlink(self.place.socket)

    def _keep_current(self) -> None:
        """Fold in discovery's news between queries, so the graph's memory follows the graph."""
        while not self.stopping.wait(0.25):
            with self.graph_lock:
                self.graph.wait_for_newcomers(0.0)
            if self.calls is not None:
                self.calls.sweep()

    def _client(self, connection: socket.socket) -> None:
        try:
            with connection:
                connection.settimeout(CLIENT_SECONDS)
                request = wire.receive(connection)
                if isinstance(request, dict) and request.get("op") == "subscribe":
                    self.relay(connection, request)
                    return
                if isinstance(request, dict) and request.get("op") == "goal":
                    self.goal(connection, request)
                    return
                reply = self.answer(request) if isinstance(request, dict) else {"error": "bad request"}
                wire.send(connection, reply)
        except wire.WireError as err:
            log.info("client dropped: %s", err)
        except Exception:
            log.exception("failed to answer")
        finally:
            self.last_request = time.monotonic()
            self.clients.release()

    def close(self) -> None:
        with self.relays_lock:
            relays = list(self.relays)
        for relay in relays:
            relay.stop()
        if self.calls is not None:
            self.calls.close()
        if self.graph is not None:
            with contextlib.suppress(Exception):
                self.graph.close()


def _guid(text: Any) -> bytes | None:
    """The asking client's own participant GUID (hex), which the daemon need not wait for."""
    try:
        return bytes.fromhex(text) if isinstance(text, str) else None
    except ValueError:
        return None


def bind(path: Path) -> socket.socket:
    """The listening socket, 0600 from its creation (umask), replacing a stale file of a dead daemon."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    old_umask = os.umask(0o177)
    try:
        listener.bind(str(path))
    finally:
        os.umask(old_umask)
    os.chmod(path, 0o600)
    listener.listen(128)
    listener.settimeout(0.5)
    return listener


@contextlib.contextmanager
def held_lock(place: DaemonPlace, wait: float) -> Iterator[IO[str] | None]:
    """The key's lock, with this pid written in it; None when another daemon keeps it past `wait` seconds
    (a replacement waits for the daemon it replaces; a daemon started with others at once does not)."""
    handle = open(place.lock, "a+", encoding="utf-8")  # noqa: SIM115 (held for the daemon's life)
    os.chmod(place.lock, 0o600)
    deadline = time.monotonic() + wait
    try:
        while True:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    yield None
                    return
                time.sleep(0.05)
        handle.truncate(0)
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        yield handle
    finally:
        handle.close()


def _setup_log() -> None:
    """stderr is the daemon's log file (its starter opened it there), so the middleware's own messages land
    in it too."""
    logging.basicConfig(
        stream=sys.stderr, level=logging.INFO, format=f"%(asctime)s [{os.getpid()}] %(levelname)s %(message)s"
    )


def run(requested: str, idle: float, replacing: bool = False, auto: bool = False) -> int:
    place = daemon_place(requested)
    _setup_log()
    daemon = Daemon(place, requested, idle, auto)
    signal.signal(signal.SIGTERM, lambda *_: daemon.stopping.set())
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # detached: only `daemon stop` or SIGTERM end it
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    with held_lock(place, LOCK_WAIT_SECONDS if replacing else 0.0) as lock:
        if lock is None:
            log.info("another daemon keeps %s: not starting", place.lock)
            return 0
        log.info("starting (build %s, key %s)", daemon.build, dict(place.fields))
        try:
            daemon.open_graph()
            if not daemon.stopping.is_set():
                daemon.serve()
        except RostoolError as err:
            log.error("%s", err)
            return 1
        finally:
            daemon.close()
            log.info("stopped")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m rostool.graph.daemon")
    parser.add_argument("--backend", choices=("auto", "rclpy", "dds"), default="auto")
    parser.add_argument("--idle", type=float, help="exit after S seconds without a query or relay")
    parser.add_argument("--replace", action="store_true", help="wait for the daemon being replaced")
    parser.add_argument("--auto", action="store_true", help="started by a verb, not by `daemon start`")
    args = parser.parse_args(argv)
    idle = args.idle
    if idle is None:
        idle = float(os.environ.get(IDLE_ENV) or (AUTO_IDLE_SECONDS if args.auto else DEFAULT_IDLE_SECONDS))
    return run(args.backend, idle, args.replace, args.auto)
