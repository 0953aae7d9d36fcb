"""The verb's side of a goal the graph daemon sends for it (goal_server.py): `action send-goal` takes the
time of the goal itself and never joins the graph (measured before: 1.65 s on the DDS backend, 1.13 s on the
rclpy one, for a 0.1 s goal). The daemon's watcher calls come back as frames and are replayed, in order,
into the verb's own renderer, their messages decoded with `CallTypes` from the daemon's definitions, so the
verb prints what the direct way prints; a --timeout's or a cancel's error is raised here as it is raised
there.

Ctrl+C: the first asks the daemon to cancel the goal (b"c") and the verb goes on reading (the canceling and
the final result are printed as the direct way prints them) until the daemon's last frame, then ends as
Ctrl+C ends it (130); a second Ctrl+C ends it at once (the daemon, seeing the connection end, cancels all
the same). The frames are read on a thread of their own, so an interrupt never cuts a frame in half. A
daemon lost mid-goal is one error line: the goal is never sent a second time.
"""

from __future__ import annotations

import base64
import contextlib
import json
import queue
import socket
import threading
from collections.abc import Callable
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import GoalEvent, GoalOutcome, GoalWatcher
from rostool.graph.daemon import wire
from rostool.graph.daemon.calls import CallTypes
from rostool.graph.daemon.client import ANSWER_SECONDS, DaemonClient, DaemonSilent, NotRelayed
from rostool.graph.daemon.relay_client import _fielddefs_from_json
from rostool.graph.ros2_base.names import resolve

GO, CANCEL = b"g", b"c"  # to the daemon: send the goal; cancel it
_LOST = b"!"  # the reading thread's own mark: the connection ended before the last frame


def send_goal_through(
    client: DaemonClient, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher,
    directly: Callable[[], GoalOutcome],
) -> GoalOutcome:  # fmt: skip
    """The goal sent by the daemon; `directly()` when the daemon cannot send it (a goal value JSON cannot
    carry, types only this process's sources define). Raises as the client's requests do (DaemonAbsent,
    DaemonSilent, OtherBuild: the caller answers directly) only before the goal may have been sent."""
    action = resolve(name)
    try:
        carried = json.loads(json.dumps(goal)) == goal
    except (TypeError, ValueError):
        carried = False
    if not carried:  # a YAML value JSON changes (a date, bytes, a number as a key): this process builds it
        return directly()
    message = {"op": "goal", "build": client.build, "action": action, "type": kind, "goal": goal,
               "timeout": timeout}  # fmt: skip
    sock = client._connect()
    try:
        answer = client._asked(sock, message, ANSWER_SECONDS)
        distro = str(answer["distro"])
        sock.sendall(GO)
    except NotRelayed:
        sock.close()
        return directly()
    except OSError as err:  # the b"g" not sent: the daemon never sends the goal
        sock.close()
        raise DaemonSilent(f"cannot send: {err}") from None
    except BaseException:
        sock.close()
        raise
    with sock:
        sock.settimeout(None)
        return GoalFollower(sock, action, CallTypes(distro), watcher).follow()


class GoalFollower:
    """Replays the daemon's frames of one goal into `watcher`, on this (the main) thread."""

    def __init__(self, sock: socket.socket, action: str, types: CallTypes, watcher: GoalWatcher) -> None:
        self._sock = sock
        self._action = action
        self._types = types
        self._watcher = watcher
        self._frames: queue.SimpleQueue[tuple[bytes, bytes]] = queue.SimpleQueue()

    def follow(self) -> GoalOutcome:
        threading.Thread(target=self._read, name=f"goal of {self._action}", daemon=True).start()
        interrupted = False
        while True:
            try:
                kind, payload = self._frames.get()
                if kind == wire.OUTCOME:
                    outcome = json.loads(payload)
                    if interrupted or outcome.get("interrupted"):
                        raise KeyboardInterrupt
                    return GoalOutcome(
                        str(outcome["goal_id"]), outcome["status"], self._decoded(outcome.get("message")),
                        str(outcome.get("text", "")), bool(outcome["canceled"]), bool(outcome["succeeded"]),
                    )  # fmt: skip
                if kind == wire.ERROR:
                    raise RostoolError(payload.decode(errors="replace"))
                if kind == _LOST:
                    lost = payload.decode(errors="replace")
                    raise RostoolError(
                        f"the graph daemon did not finish the goal of {self._action} (it may have been "
                        f"sent): {lost}; see `rostool action list` and send it again"
                    )
                if kind == wire.TYPE:
                    self._learn(payload)
                elif kind == wire.GOAL:
                    self._replay(json.loads(payload))
            except KeyboardInterrupt:
                if interrupted:  # a second Ctrl+C: the daemon cancels when the connection ends
                    raise
                interrupted = True
                with contextlib.suppress(OSError):  # the daemon gone: its frames say so
                    self._sock.sendall(CANCEL)

    def _read(self) -> None:
        stream = self._sock.makefile("rb")
        try:
            while True:
                kind, _stamp, payload = wire.receive_frame(stream)
                self._frames.put((kind, payload))
                if kind in (wire.OUTCOME, wire.ERROR):
                    return
        except wire.WireError as err:
            self._frames.put((_LOST, str(err).encode()))
        finally:
            stream.close()

    def _replay(self, call: dict[str, Any]) -> None:
        watcher, what = self._watcher, call.get("call")
        if what == "sent":
            watcher.sent(str(call["goal_id"]), self._decoded(call.get("goal")), bool(call["accepted"]))
        elif what == "event":
            message = self._decoded(call.get("message"))
            event = GoalEvent(str(call["kind"]), int(call["status"]), str(call["status_name"]), message,
                              str(call.get("text", "")))  # fmt: skip
            watcher.event(event)
        elif what == "waiting":
            watcher.waiting(str(call["text"]))
        elif what == "canceling":
            watcher.canceling(str(call["goal_id"]))

    def _decoded(self, message: dict[str, str] | None) -> Any:
        if message is None:
            return None
        return self._types.store.deserialize_cdr(base64.b64decode(message["cdr"]), message["type"])

    def _learn(self, payload: bytes) -> None:
        """A type of the goal's messages from the daemon's description (goal_server's): rosbags' field
        definitions of it and of what it nests, those this process lacks."""
        described = json.loads(payload)
        name = str(described["name"])
        if self._types.in_store(name):
            return
        with contextlib.suppress(Exception):  # unreadable: this process's own sources may know it
            found = _fielddefs_from_json(described.get("fielddefs") or {})
            self._types.register({n: defs for n, defs in found.items() if not self._types.in_store(n)})
        if not self._types.in_store(name):
            with contextlib.suppress(Exception):  # the decoder names the type when it is still unknown
                self._types.knows(name)
