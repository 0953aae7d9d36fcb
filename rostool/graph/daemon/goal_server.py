"""The daemon's side of `action send-goal` made for a verb: the daemon's graph already knows the action's
server, so its action client matches at once and the verb's process never joins the graph. The daemon runs
its own graph's `send_goal` with a watcher that streams every call the goal's run makes (sent, waiting,
event, canceling) back to the verb, which replays them into its own renderer: the verb prints what the
direct way prints.

On its own connection (wire.py): {"op": "goal", "build", "action", "type" (or null), "goal" (the goal's
YAML value as JSON), "timeout" (or null)} is answered like a query ({"ok": {"distro"}}, {"error": one line}
(an unknown action), or {"direct": why}: the daemon cannot build the action's types, the verb's own sources
may), then the verb sends one byte, b"g", before the goal is sent: a verb that gave up waiting for the
answer (and runs the goal itself) has closed the connection instead, so a goal is never sent twice. Then
frames: TYPE (a type's definition, before its first message), GOAL (a watcher's call, JSON: messages as
CDR in base64 with their type name) and one last frame, OUTCOME (the GoalOutcome, or {"interrupted": true})
or ERROR (the one-line RostoolError the run ended with, e.g. a --timeout's). A b"c" from the verb, or its
end of the connection (Ctrl+C, exit, kill -9), cancels the goal as Ctrl+C cancels a direct one.

The cancel is the watcher's `cancel_asked` (an Event): each backend's wait loops check it
(ros2_base/actions.stop_if_asked) and raise KeyboardInterrupt there, so the goal is canceled exactly as a
Ctrl+C cancels a direct one (the server told, the canceling and the final result reported), at a point
where the run holds no lock of the long-lived graph's (an exception raised into the thread from outside
could land anywhere, and a lock left held would stop the daemon).
"""

from __future__ import annotations

import base64
import contextlib
import json
import logging
import queue
import socket
import threading
import time
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import GoalEvent
from rostool.graph.daemon import wire
from rostool.graph.daemon.relay_server import _closure
from rostool.graph.ros2_base.actions import action_type
from rostool.graph.ros2_base.names import resolve

GO, CANCEL = b"g", b"c"  # from the verb: send the goal; cancel it
GO_SECONDS = 5.0  # the verb's b"g" after the answer (it has the answer already: at once)
log = logging.getLogger("rostool.daemon")
Frame = tuple[bytes, int, bytes]
Item = dict[str, Any] | Frame | None  # a watcher's call (or the outcome), an ERROR frame, or the end


class GoalRun:
    """One verb's goal: checked and answered on the client's thread, run on a thread of its own."""

    def __init__(
        self, graph: Any, graph_lock: threading.Lock, connection: socket.socket, backend: str
    ) -> None:
        self.graph = graph
        self.graph_lock = graph_lock
        self.connection = connection
        self.backend = backend
        self.action = ""
        self._frames: queue.SimpleQueue[Item] = queue.SimpleQueue()
        self._described: set[str] = set()
        self._state = threading.Lock()
        self._running = False  # send_goal is running
        self._watcher = StreamingWatcher(self._frames)
        self._thread: threading.Thread | None = None

    def serve(self, request: dict[str, Any]) -> None:
        """Answer the request, then (once the verb says go) run the goal until it ends."""
        answer, kind = self._check(request)
        wire.send(self.connection, answer)
        if "ok" not in answer:
            return
        self.connection.settimeout(GO_SECONDS)
        try:
            go = self.connection.recv(1)
        except OSError:
            go = b""
        if go != GO:
            log.info("goal of %s: the verb did not go on", self.action)
            return
        timeout = request.get("timeout")
        limit = float(timeout) if isinstance(timeout, (int, float)) else None
        sender = threading.Thread(target=self._send, name=f"goal frames {self.action}", daemon=True)
        sender.start()
        self._thread = threading.Thread(
            target=self._run, args=(kind, request.get("goal"), limit), name=f"goal {self.action}", daemon=True
        )
        with self._state:
            self._running = True  # before the thread starts: a cancel that comes at once is not lost
        self._thread.start()
        log.info("goal of %s sent for a verb", self.action)
        self.connection.settimeout(None)
        while self._thread.is_alive():
            try:
                data = self.connection.recv(64)
            except OSError:
                data = b""
            if not data or CANCEL in data:  # the verb's Ctrl+C, or the verb is gone
                self.cancel()
                break
        self._thread.join()
        sender.join(5.0)
        log.info("goal of %s ended", self.action)

    def _check(self, request: dict[str, Any]) -> tuple[dict[str, Any], str]:
        """The answer before anything is sent, and the action's type: an unknown action is the direct
        way's error; types the daemon cannot build send the verb the direct way."""
        name, kind = request.get("action"), request.get("type")
        if not isinstance(name, str) or not (kind is None or isinstance(kind, str)):
            return {"error": "graph daemon: a goal names its action, and its type or null"}, ""
        self.action = resolve(name)
        try:
            with self.graph_lock:  # the graph's look at its actions, and types registered, beside queries
                found = action_type(self.graph, self.action, kind)
        except RostoolError as err:
            return {"error": str(err)}, ""
        try:
            with self.graph_lock:
                self._register(found)
        except RostoolError as err:  # the verb's own sources (--interfaces) may define it
            return {"direct": str(err)}, ""
        return {"ok": {"distro": str(self.graph.types.distro)}}, found

    def _register(self, kind: str) -> None:
        if self.backend == "rclpy":  # a type rosbags lacks is described from the class rclpy imports
            from rostool.graph.rclpy.actions import register_action

            register_action(self.graph, kind)
            return
        from rostool.interfaces.ros2_action import register_action as register_dds

        register_dds(self.graph.types, kind)

    # --- the goal's thread ---------------------------------------------------------------------------
    def _run(self, kind: str, goal: Any, timeout: float | None) -> None:
        end: Item
        try:
            outcome = self.graph.send_goal(self.action, kind, goal, timeout, self._watcher)
            end = {
                "call": "outcome", "goal_id": outcome.goal_id, "status": outcome.status, "text": outcome.text,
                "canceled": outcome.canceled, "succeeded": outcome.succeeded, "message": outcome.result,
            }  # fmt: skip
        except KeyboardInterrupt:  # the verb's cancel: the goal was canceled as a direct Ctrl+C cancels it
            end = {"call": "outcome", "interrupted": True}
        except RostoolError as err:
            end = (wire.ERROR, 0, str(err).encode())
        except Exception as err:
            log.exception("goal of %s failed", self.action)
            end = (wire.ERROR, 0, f"graph daemon: the goal of {self.action} failed: {err}".encode())
        finally:
            with self._state:
                self._running = False
        self._frames.put(end)
        self._frames.put(None)

    def cancel(self) -> None:
        """Cancel the goal as Ctrl+C would (see the module's docstring), while it runs."""
        with self._state:
            if not self._running or self._watcher.cancel_asked.is_set():
                return
            self._watcher.cancel_asked.set()
        log.info("goal of %s: canceled for the verb", self.action)

    # --- the sender's thread: messages encoded and written here, never in the goal's thread -------------
    def _send(self) -> None:
        try:
            while True:
                item = self._frames.get()
                if item is None:
                    return
                frames = self._encoded(item) if isinstance(item, dict) else [item]
                wire.send_frames(self.connection, frames)
        except wire.WireError as err:  # the verb is gone: its end of the connection cancels the goal
            log.info("goal of %s: frames not sent: %s", self.action, err)
        finally:
            while self._frames.get() is not None:  # the goal's thread puts None last
                pass

    def _encoded(self, call: dict[str, Any]) -> list[Frame]:
        """A watcher's call as a GOAL frame (the outcome as the OUTCOME frame), its messages as CDR, after
        the TYPE frames of the types the verb has not been told of yet."""
        types: list[Frame] = []
        for key in ("goal", "message"):
            if key in call:
                call[key] = self._message(call[key], types)
        kind = wire.OUTCOME if call["call"] == "outcome" else wire.GOAL
        return [*types, (kind, time.time_ns(), json.dumps(call).encode())]

    def _message(self, message: Any, types: list[Frame]) -> dict[str, str] | None:
        """A message as {"type", "cdr"}; its type's TYPE frame, the first time, into `types`."""
        if message is None:
            return None
        type_name = str(message.__msgtype__)
        store = self.graph.types.store
        if type_name not in self._described:
            self._described.add(type_name)
            types.append((wire.TYPE, 0, _described(store, type_name)))
        cdr = bytes(store.serialize_cdr(message, type_name))
        return {"type": type_name, "cdr": base64.b64encode(cdr).decode()}


class StreamingWatcher:
    """The GoalWatcher `send_goal` runs with in the daemon: each call is put, as it is, in the sender's
    queue (the sender encodes and writes it)."""

    def __init__(self, frames: queue.SimpleQueue[Item]) -> None:
        self._frames = frames
        self.cancel_asked = threading.Event()  # the verb's Ctrl+C: the run cancels at its next wait

    def sent(self, goal_id: str, goal: Any = None, accepted: bool = True) -> None:
        self._frames.put({"call": "sent", "goal_id": goal_id, "goal": goal, "accepted": accepted})

    def event(self, event: GoalEvent) -> None:
        self._frames.put({
            "call": "event", "kind": event.kind, "status": event.status, "status_name": event.status_name,
            "message": event.message, "text": event.text,
        })  # fmt: skip

    def waiting(self, text: str) -> None:
        self._frames.put({"call": "waiting", "text": text})

    def canceling(self, goal_id: str) -> None:
        self._frames.put({"call": "canceling", "goal_id": goal_id})


def _described(store: Any, type_name: str) -> bytes:
    """A type as rosbags' field definitions of it and of every type it nests (relay_server's `_closure`):
    .msg text would lose a `byte` or a `char` to `uint8`, and rosbags writes none for `pkg/action/X_Goal`."""
    described: dict[str, Any] = {"name": type_name, "definition": ""}
    with contextlib.suppress(Exception):  # none: the verb's own types decide
        described["fielddefs"] = _closure(store.fielddefs, type_name)
    return json.dumps(described).encode()
