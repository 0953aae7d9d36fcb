"""`topic pub`: build messages from YAML and publish them once, latched, or at a steady rate."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

from rostool.errors import RostoolError, yaml_problem
from rostool.graph.base import Graph
from rostool.interfaces.values import message_args

ONCE_LATCH_SECONDS = 3.0
MATCH_WAIT_SECONDS = 3.0  # ROS 2: how long a finite publication waits for the subscribers discovered


def _file_messages(path: str) -> list[Any]:
    try:
        docs = [doc for doc in yaml.safe_load_all(Path(path).read_text()) if doc is not None]
    except OSError as err:
        raise RostoolError(f"cannot read messages from {path}: {err.strerror or err}") from err
    except yaml.YAMLError as err:
        raise RostoolError(f"cannot read messages from {path}: bad YAML: {yaml_problem(err)}") from err
    if not docs:
        raise RostoolError(f"{path} holds no messages (YAML documents separated by ---)")
    return docs


def publish_loop(
    graph: Graph,
    topic: str,
    type_name: str,
    values: tuple[str, ...],
    *,
    rate: float | None,
    once: bool,
    latch: bool,
    count: int | None,
    file: str | None,
    say: Callable[[str], None],
) -> None:
    raw = _file_messages(file) if file else [message_args(values)]
    messages = [graph.build_message(type_name, value) for value in raw]
    latched = latch or rate is None
    publisher = graph.publisher(topic, type_name, latch=latched)
    finite = rate is None or once or count is not None or file is not None
    if graph.ros_version == 2 and finite:
        # A volatile ROS 2 subscriber gets nothing published before it matched (latching only serves
        # transient_local ones), so wait for the subscribers discovery shows, as ros2 topic pub -1 does.
        _wait_for_known_subscribers(graph, publisher, MATCH_WAIT_SECONDS)
    if rate is None and not file:
        publisher.publish(messages[0])
        if once:
            say(f"publishing and latching message for {ONCE_LATCH_SECONDS:.1f} seconds")
            _linger(graph, publisher, ONCE_LATCH_SECONDS)
            return
        say("publishing and latching message. Press ctrl-C to terminate")
        while True:
            time.sleep(3600)
    period = 1.0 / (rate or 10.0)
    total = count if count is not None else (len(messages) if file and rate is None else None)
    if once:
        total = len(messages)
    say(f"publishing {type_name} on {topic}" + (f" at {rate:g} Hz" if rate else ""))
    # Absolute scheduling: each message has its own due time, so the rate never drifts.
    start = time.perf_counter()
    sent = 0
    while total is None or sent < total:
        due = start + sent * period
        delay = due - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        publisher.publish(messages[sent % len(messages)])
        sent += 1
    if latched or once:
        _linger(graph, publisher, min(ONCE_LATCH_SECONDS, 1.0))


def _linger(graph: Graph, publisher: Any, seconds: float) -> None:
    """Stay up until every subscriber the graph knows has connected (at most `seconds`)."""
    deadline = time.monotonic() + seconds
    _wait_for_known_subscribers(graph, publisher, seconds)
    time.sleep(max(0.0, deadline - time.monotonic()))


def _wait_for_known_subscribers(graph: Graph, publisher: Any, seconds: float) -> None:
    deadline = time.monotonic() + seconds
    try:
        wanted = len(next((t.subscribers for t in graph.topics() if t.name == publisher.topic), []))
    except RostoolError:  # nobody else in the graph (ROS 2: no participant answered)
        return
    publisher.wait_for_subscribers(wanted, max(0.0, deadline - time.monotonic()))
