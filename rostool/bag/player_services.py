"""rosbag2's control services: `bag play` on a ROS 2 graph serves the player's (`/rosbag2_player/pause`,
`resume`, `toggle_paused`, `is_paused`, `get_rate`, `set_rate`, `play_next`, `burst`, `seek`, `stop`) and
`ros2 bag record` the recorder's (`/rosbag2_recorder/pause`, `resume`, `is_paused`, and `snapshot` in
snapshot mode), with rosbag2_interfaces' types (built into rostool: interfaces/rosbag2_srv.py).

A request arrives on a thread of the transport; `Controls` hands it to the player's loop, which acts on
it as on a key (play.py `Player._command`) and answers. A service that cannot be served (the rclpy
backend where rosbag2_interfaces is not installed) leaves playing and recording as they are, with one
warning.
"""

from __future__ import annotations

import contextlib
import queue
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.base import Graph, ServedService

PLAYER_NODE = "/rosbag2_player"  # rosbag2's player node: its services are under it
_TYPES = "rosbag2_interfaces/srv/"
MAKE_SECONDS = 10.0  # the most a verb's end waits for its services still being made (ServedLater)


def _no_value(_request: Any) -> None:
    return None


def _time_ns(request: Any) -> int:
    return int(request.time.sec) * 1_000_000_000 + int(request.time.nanosec)


# service -> (type, the request's value for the player)
PLAYER_SERVICES: dict[str, tuple[str, Callable[[Any], Any]]] = {
    "pause": ("Pause", _no_value),
    "resume": ("Resume", _no_value),
    "toggle_paused": ("TogglePaused", _no_value),
    "is_paused": ("IsPaused", _no_value),
    "get_rate": ("GetRate", _no_value),
    "set_rate": ("SetRate", lambda request: float(request.rate)),
    "play_next": ("PlayNext", _no_value),
    "burst": ("Burst", lambda request: int(request.num_messages)),
    "seek": ("Seek", _time_ns),
    "stop": ("Stop", _no_value),
}


@dataclass
class Command:
    """One service request for the player's loop: `name` (the service's) and the request's value."""

    name: str
    value: Any = None
    answer: dict[str, Any] = field(default_factory=dict)
    done: threading.Event = field(default_factory=threading.Event)

    def reply(self, **fields: Any) -> None:
        self.answer = fields
        self.done.set()


class Controls:
    """Requests from the services' threads, taken and answered by the player's loop (`pending`); once
    closed, what is left is answered with the response's defaults."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[Command] = queue.SimpleQueue()
        self._closed = threading.Event()

    def ask(self, name: str, value: Any = None) -> dict[str, Any]:
        command = Command(name, value)
        if self._closed.is_set():
            return {}
        self._queue.put(command)
        while not command.done.wait(0.1):
            if self._closed.is_set():
                break
        return command.answer

    def pending(self) -> list[Command]:
        found = []
        with contextlib.suppress(queue.Empty):
            while True:
                found.append(self._queue.get_nowait())
        return found

    def close(self) -> None:
        self._closed.set()
        for command in self.pending():
            command.reply()


class Served:
    """The services one player or recorder serves; `close()` ends them."""

    def __init__(self, services: Sequence[ServedService] = ()) -> None:
        self.services = list(services)

    def __bool__(self) -> bool:
        return bool(self.services)

    def close(self) -> None:
        for service in self.services:
            with contextlib.suppress(Exception):
                service.close()
        self.services.clear()


class ServedLater:
    """Services made on a thread of their own (`make()`), so what the verb does first is not held up by
    them: `bag record` subscribes at once while its recorder services (0.6 s of type building on the DDS
    backend) are made beside it. `close` waits for them to be made, then closes them."""

    def __init__(self, make: Callable[[], Served]) -> None:
        self._served: Served | None = None
        self._thread = threading.Thread(target=self._make, args=(make,), name="services", daemon=True)
        self._thread.start()

    def _make(self, make: Callable[[], Served]) -> None:
        # the verb may end under it (Ctrl+C while starting: its graph closed); `serve` says in one line why
        # a service itself could not be made
        with contextlib.suppress(Exception):
            self._served = make()

    def close(self) -> None:
        self._thread.join(MAKE_SECONDS)
        if self._served is not None:
            self._served.close()


def serve(
    graph: Graph,
    node: str,
    handlers: Mapping[str, tuple[str, Callable[[Any], Mapping[str, Any]]]],
    warn: Callable[[str], None],
) -> Served:
    """Serve `node`/NAME for each NAME -> (type in rosbag2_interfaces, handler); none when one fails (one
    warning saying why)."""
    served = Served()
    try:
        for name, (type_name, handler) in handlers.items():
            served.services.append(graph.serve_service(f"{node}/{name}", _TYPES + type_name, handler))
    except RostoolError as err:
        served.close()
        warn(f"{node}'s services are not served: {err}")
    return served


def serve_player(graph: Graph, controls: Controls, warn: Callable[[str], None]) -> Served:
    def handler(name: str, value_of: Callable[[Any], Any]) -> Callable[[Any], Mapping[str, Any]]:
        return lambda request: controls.ask(name, value_of(request))

    handlers = {name: (kind, handler(name, value_of)) for name, (kind, value_of) in PLAYER_SERVICES.items()}
    return serve(graph, PLAYER_NODE, handlers, warn)


def serve_recorder(
    graph: Graph,
    node: str,
    paused: Callable[[], bool],
    toggle: Callable[[], None],
    snapshot: Callable[[], bool] | None,
    split: Callable[[], object],
    warn: Callable[[str], None],
) -> Served:
    """The recorder's NODE/pause, resume, is_paused and split_bagfile (rosbag2's `/rosbag2_recorder/...`;
    `split()` returns once the next file is started), and in snapshot mode NODE/snapshot: `snapshot()`
    writes the snapshot and says whether it was written."""
    lock = threading.Lock()

    def set_paused(wanted: bool) -> dict[str, Any]:
        with lock:
            if paused() != wanted:
                toggle()
        return {}

    def split_file() -> dict[str, Any]:
        split()
        return {}

    handlers: dict[str, tuple[str, Callable[[Any], Mapping[str, Any]]]] = {
        "pause": ("Pause", lambda _request: set_paused(True)),
        "resume": ("Resume", lambda _request: set_paused(False)),
        "is_paused": ("IsPaused", lambda _request: {"paused": paused()}),
        "split_bagfile": ("SplitBagfile", lambda _request: split_file()),
    }
    if snapshot is not None:
        handlers["snapshot"] = ("Snapshot", lambda _request: {"success": snapshot()})
    return serve(graph, node, handlers, warn)
