"""`topic pub`: build messages from YAML and publish them once, latched, or at a steady rate (rostopic pub's
loop), or at a rate a number of times after waiting for subscriptions (ros2 topic pub's)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from rostool.errors import RostoolError, yaml_problem
from rostool.graph.base import Graph
from rostool.interfaces.values import message_args

ONCE_LATCH_SECONDS = 3.0
MATCH_WAIT_SECONDS = 3.0  # ROS 2: how long a finite publication waits for the subscribers discovered to match


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
    _paced(period, total, lambda sent: publisher.publish(messages[sent % len(messages)]))
    if latched or once:
        _linger(graph, publisher, min(ONCE_LATCH_SECONDS, 1.0))


def _linger(graph: Graph, publisher: Any, seconds: float) -> None:
    """Stay up until every subscriber the graph knows has connected (at most `seconds`)."""
    deadline = time.monotonic() + seconds
    _wait_for_known_subscribers(graph, publisher, seconds)
    time.sleep(max(0.0, deadline - time.monotonic()))


def _wait_for_known_subscribers(graph: Graph, publisher: Any, seconds: float, least: int = 0) -> None:
    """Wait for the event itself: every subscriber the graph knows of has matched this publisher (its
    matched count). `seconds` bounds only that wait, counted once the graph has answered: a direct ROS 2
    listing spends its own discovery time first, and a subscriber it lists still has to discover this
    new publisher (Fast DDS: on its next announcement), so a window that included the listing ran out
    before the match and the message went to nobody. `least`: wait for at least that many matches even
    when the graph lists fewer."""
    try:
        wanted = len(next((t.subscribers for t in graph.topics() if t.name == publisher.topic), []))
    except RostoolError:  # nobody else in the graph (ROS 2: no participant answered in its window)
        return
    publisher.wait_for_subscribers(max(wanted, least), seconds)


def _paced(period: float, total: int | None, publish: Callable[[int], None]) -> None:
    """publish(0), publish(1), ... (`total` times, or until Ctrl+C), one every `period` seconds.

    Absolute scheduling: each message has its own due time, so the rate never drifts."""
    start = time.perf_counter()
    sent = 0
    while total is None or sent < total:
        delay = start + sent * period - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        publish(sent)
        sent += 1


@dataclass(frozen=True)
class Ros2Publication:
    """ros2 topic pub's loop: `total` messages (None: until Ctrl+C) at `rate` Hz, after `wait_matching`
    subscriptions matched (at most `max_wait` s), staying up `keep_alive` s after the last."""

    rate: float
    total: int | None
    wait_matching: int | None
    max_wait: float | None
    keep_alive: float


def publish_ros2(
    graph: Graph,
    topic: str,
    type_name: str,
    values: tuple[str, ...],
    plan: Ros2Publication,
    say: Callable[[str], None],
    on_sent: Callable[[int, Any], None] | None,
) -> None:
    """ros2 topic pub: wait for subscriptions, publish at the rate; `on_sent(count, message)` after each
    message (when given, "publisher: beginning loop" is said first)."""
    raw = _auto_values(message_args(values))
    rebuild = "now" in repr(raw)  # a stamp of `now` is taken again for every message
    message = graph.build_message(type_name, raw)
    publisher = graph.publisher(topic, type_name, latch=False)
    if plan.wait_matching:
        deadline = None if plan.max_wait is None else time.monotonic() + plan.max_wait
        wait = 0.0
        while not publisher.wait_for_subscribers(plan.wait_matching, wait):  # ros2's line, once a second
            if deadline is not None and time.monotonic() >= deadline:
                raise RostoolError(f"timed out waiting for {plan.wait_matching} matching subscription(s)")
            say(f"Waiting for at least {plan.wait_matching} matching subscription(s)...")
            wait = 1.0
    elif plan.total is not None:
        # a volatile subscriber gets nothing published before it matched: wait for the ones the graph
        # knows and, as ros2 topic pub -1/-t does, for at least one (a direct listing may not know of a
        # subscriber yet) unless -w 0 said not to
        least = 0 if plan.wait_matching == 0 else 1
        seconds = MATCH_WAIT_SECONDS if plan.max_wait is None else min(plan.max_wait, MATCH_WAIT_SECONDS)
        _wait_for_known_subscribers(graph, publisher, seconds, least)
    if on_sent is not None:
        say("publisher: beginning loop")

    def publish(sent: int) -> None:
        nonlocal message
        if rebuild and sent:
            message = graph.build_message(type_name, raw)
        publisher.publish(message)
        if on_sent is not None:
            on_sent(sent + 1, message)

    _paced(1.0 / plan.rate, plan.total, publish)
    time.sleep(plan.keep_alive)


def _auto_values(value: Any) -> Any:
    """ros2 topic pub's `header: auto` (stamp now, empty frame) as rostool's `stamp: now`."""
    if isinstance(value, dict):
        return {
            k: {"stamp": "now"} if k == "header" and v == "auto" else _auto_values(v)
            for k, v in value.items()
        }
    if isinstance(value, list):
        return [_auto_values(v) for v in value]
    return value
