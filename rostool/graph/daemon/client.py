"""Reaching the daemon of this environment's key: asking it, starting it detached, stopping it.

The socket is checked before connecting (a socket, this user's, 0600, in a private directory). No socket
or a refused connection while the key's lock is free means no daemon (or a dead one's stale socket): it
is started. The lock held without an answering socket means one is starting.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import signal
import socket
import stat
import subprocess
import sys
import time
from collections.abc import Mapping
from typing import IO, Any

from rostool.errors import RostoolError
from rostool.graph.daemon import NO_DAEMON_ENV, wire
from rostool.graph.daemon.place import (
    DaemonPlace,
    PlaceRefused,
    build_id,
    daemon_place,
    private_dir,
    state_dir,
)

CONNECT_SECONDS = 0.5
ANSWER_SECONDS = 3.0  # a query's answer; past it the verb answers directly
START_SECONDS = 15.0  # `daemon start`: discovery settles (up to 4.5 s) before the socket is bound


class DaemonAbsent(Exception):
    """No daemon answers on the socket (none, a stale socket, or one still starting)."""


class DaemonSilent(Exception):
    """A daemon took the connection but did not answer in time, or broke the protocol."""


class NotRelayed(Exception):
    """The daemon cannot relay this subscription (too many at once): the verb subscribes itself."""


class OtherBuild(Exception):
    """The daemon is of another rostool build; it stops itself to be replaced."""


class DaemonClient:
    def __init__(
        self, requested_backend: str, env: Mapping[str, str] = os.environ, place: DaemonPlace | None = None
    ) -> None:
        self.requested = requested_backend
        self.env = env
        self.place: DaemonPlace = place or daemon_place(requested_backend, env)
        self._build: str | None = None
        self._cold: IO[str] | None = None  # the key's cold-call claim, once this process holds it

    @property
    def build(self) -> str:
        if self._build is None:
            self._build = build_id(self.env)
        return self._build

    # --- asking ----------------------------------------------------------------------------------
    def request(self, message: dict[str, Any], timeout: float | None = ANSWER_SECONDS) -> Any:
        """The daemon's answer's value; RostoolError for the backend's own one-line errors."""
        sock = self._connect()
        with sock:
            return self._asked(sock, message, timeout)

    def relay(self, topic: str, qos: dict[str, Any]) -> socket.socket:
        """A connection on which the daemon streams `topic`'s messages (wire.py's frames) until it is
        closed; raises as `request` does, and NotRelayed when the daemon cannot serve it."""
        sock = self._connect()
        try:
            self._asked(sock, {"op": "subscribe", "build": self.build, "topic": topic, "qos": qos})
        except BaseException:
            sock.close()
            raise
        sock.settimeout(None)
        return sock

    @staticmethod
    def _asked(sock: socket.socket, message: dict[str, Any], timeout: float | None = ANSWER_SECONDS) -> Any:
        sock.settimeout(timeout)
        try:
            wire.send(sock, message)
            answer = wire.receive(sock)
        except wire.WireError as err:
            raise DaemonSilent(str(err)) from None
        if isinstance(answer, dict) and "direct" in answer:
            raise NotRelayed(str(answer["direct"]))
        if not isinstance(answer, dict):
            raise DaemonSilent("an answer that is not an object")
        if "build" in answer:
            raise OtherBuild(str(answer["build"]))
        if "error" in answer:
            raise RostoolError(str(answer["error"]))
        if "ok" not in answer:
            raise DaemonSilent("an answer without a value")
        return answer["ok"]

    def query(self, method: str, args: list[Any], own: bytes | None = None) -> Any:
        """A Graph method's answer; `own`: the asking process's participant, which the daemon need not wait
        for to describe itself."""
        message = {"op": "query", "build": self.build, "method": method, "args": args}
        if own is not None:
            message["own"] = own.hex()
        return self.request(message)

    def _connect(self) -> socket.socket:
        path = self.place.socket
        try:
            info = path.lstat()
        except FileNotFoundError:
            raise DaemonAbsent("no socket") from None
        if not stat.S_ISSOCK(info.st_mode) or info.st_uid != os.getuid() or info.st_mode & 0o077:
            raise PlaceRefused(
                f"{path} is not a private socket of yours (uid {info.st_uid}, mode "
                f"{stat.S_IMODE(info.st_mode):o}): the graph daemon refuses it; remove it"
            )
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.settimeout(CONNECT_SECONDS)
        try:
            sock.connect(str(path))
        except (ConnectionRefusedError, FileNotFoundError):
            sock.close()
            raise DaemonAbsent("stale socket") from None
        except OSError as err:
            sock.close()
            raise DaemonSilent(f"cannot connect: {err}") from None
        return sock

    # --- life ------------------------------------------------------------------------------------
    def lock_holder(self) -> int | None:
        """The pid of the daemon holding the key's lock (running or starting), None when it is free."""
        text = _held(str(self.place.lock))
        if text is None:
            return None
        return int(text) if text.isdigit() else -1

    def claim_cold_call(self) -> bool:
        """Whether this process is its key's cold call: the one that answers directly and starts the
        daemon (an exclusive lock on the key's `.cold` file, held for this process's life and by the
        daemon it starts). Calls made meanwhile wait for that daemon: each answering directly would be one
        more participant (a burst of them fails, past the DDS participants a host can hold)."""
        if self._cold is not None:
            return True
        handle = os.fdopen(os.open(self._cold_path(), os.O_RDWR | os.O_CREAT, 0o600), "r+")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            return False
        self._cold = handle
        return True

    def cold_call_elsewhere(self) -> bool:
        """Whether another process holds the key's cold-call claim (a cold call, or the daemon it started)."""
        return self._cold is None and _held(self._cold_path()) is not None

    def _cold_path(self) -> str:
        return str(self.place.lock.with_name(f"{self.place.name}.cold"))

    def start_detached(
        self, idle: float | None = None, replacing: bool = False, auto: bool = False
    ) -> subprocess.Popen[bytes]:
        """Start the daemon in its own session, its output in its log; the caller does not wait for it.
        `auto`: a verb starts it for itself (it then ends sooner when idle: server.AUTO_IDLE_SECONDS)."""
        log_dir = private_dir(state_dir(self.env))
        # glibc's per-thread malloc arenas (DDS runs many threads) grow a long-lived process's RSS slowly
        # under churn (about 0.1 MiB a minute in bench/soak_daemon.py); two arenas keep it flat
        env = {"MALLOC_ARENA_MAX": "2", **self.env, NO_DAEMON_ENV: "1"}
        args = [sys.executable, "-m", "rostool.graph.daemon", "--backend", self.requested]
        if idle is not None:
            args += ["--idle", str(idle)]
        if replacing:
            args.append("--replace")
        if auto:
            args.append("--auto")
        # the daemon keeps this process's cold-call claim: the calls waiting for it go on waiting after
        # this process has ended, until it serves (or ends)
        claim = (self._cold.fileno(),) if self._cold is not None else ()
        with open(log_dir / self.place.log.name, "a", encoding="utf-8") as log:
            os.chmod(log.name, 0o600)
            return subprocess.Popen(
                args, env=env, stdin=subprocess.DEVNULL, stdout=log, stderr=log, cwd="/",
                start_new_session=True, close_fds=True, pass_fds=claim,
            )  # fmt: skip

    def status(self) -> dict[str, Any] | None:
        """The running daemon's status; None when none runs."""
        try:
            found = self.request({"op": "status"})
        except DaemonAbsent:
            return None
        return found if isinstance(found, dict) else None

    def wait_ready(
        self, started: subprocess.Popen[bytes] | None, timeout: float = START_SECONDS
    ) -> dict[str, Any] | None:
        """The status once the daemon answers; None when it gave up (its log says why) or took too long."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with contextlib.suppress(DaemonAbsent, DaemonSilent):
                found = self.status()
                if found is not None:
                    return found
            if started is not None and started.poll() is not None and self.lock_holder() is None:
                return None  # it gave up, and no other daemon is starting
            time.sleep(0.05)
        return None

    def stop(self, timeout: float = 5.0) -> bool:
        """Stop the daemon (asked, then SIGTERM, then SIGKILL); whether one was running."""
        holder = self.lock_holder()
        asked = False
        with contextlib.suppress(DaemonAbsent, DaemonSilent, RostoolError):
            self.request({"op": "stop"})
            asked = True
        if holder is None and not asked:
            return False
        deadline = time.monotonic() + timeout
        for sig in (None, signal.SIGTERM, signal.SIGKILL):
            if sig is not None and holder and holder > 0:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(holder, sig)
            while time.monotonic() < deadline:
                if self.lock_holder() is None:
                    self._remove_stale_socket()
                    return True
                time.sleep(0.05)
            deadline = time.monotonic() + 2.0
        return True

    def _remove_stale_socket(self) -> None:
        """A socket left by a killed daemon refuses connections: remove it."""
        probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        with probe, contextlib.suppress(OSError):
            try:
                probe.connect(str(self.place.socket))
            except ConnectionRefusedError:
                os.unlink(self.place.socket)


def _held(path: str) -> str | None:
    """The text of a lock file that a process holds (flock), None when it is free or missing."""
    try:
        handle = open(path, encoding="utf-8")  # noqa: SIM115
    except FileNotFoundError:
        return None
    with handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return handle.read().strip()
        fcntl.flock(handle, fcntl.LOCK_UN)
        return None


def every_daemon(env: Mapping[str, str] = os.environ) -> list[DaemonClient]:
    """A client of each daemon that has a lock file in this user's directory (any key)."""
    from rostool.graph.daemon.place import runtime_dir

    folder = private_dir(runtime_dir(env), create=False)
    found = []
    for lock in sorted(folder.glob("*.lock")) if folder.is_dir() else []:
        name = lock.stem
        place = DaemonPlace(name, lock.with_suffix(".sock"), lock, state_dir(env) / f"{name}.log", ())
        found.append(DaemonClient(name.split("-")[0], env, place))
    return found
