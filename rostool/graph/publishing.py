"""`topic pub`: build messages from YAML and publish them once, latched, or at a steady rate (rostopic pub's
loop), or at a rate a number of times after waiting for subscriptions (ros2 topic pub's)."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from rostool.errors import RostoolError, yaml_problem
from rostool.graph.base import Graph
from rostool.interfaces.values import message_args

ONCE_LATCH_SECONDS = 3.0
MATCH_WAIT_SECONDS = 3.0  # how long a first message waits for the subscribers the graph shows (--match-wait)


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
    match_wait: float = MATCH_WAIT_SECONDS,
    warn: Callable[[str], None] = lambda _text: None,
) -> None:
    raw = _file_messages(file) if file else [message_args(values)]
    messages = [graph.build_message(type_name, value) for value in raw]
    latched = latch or rate is None
    publisher = graph.publisher(topic, type_name, latch=latched)
    # A subscriber gets nothing published before it matched (ROS 1: connected; latching only serves
    # transient_local ones in ROS 2), so the first message waits for the subscribers the graph shows.
    _match_or_warn(graph, publisher, match_wait, warn)
    if rate is None and not file:
        publisher.publish(messages[0])
        if once:
            say(f"publishing and latching message for {ONCE_LATCH_SECONDS:.1f} seconds")
            _linger(graph, publisher, ONCE_LATCH_SECONDS, asked=match_wait > 0)
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
        _linger(graph, publisher, min(ONCE_LATCH_SECONDS, 1.0), asked=match_wait > 0)


def _linger(graph: Graph, publisher: Any, seconds: float, asked: bool = False) -> None:
    """Stay up `seconds`, until every subscriber the graph knows has connected at least; `asked`: they
    were waited for before publishing (the graph is not asked twice)."""
    deadline = time.monotonic() + seconds
    if not asked:
        _wait_for_known_subscribers(graph, publisher, seconds)
    time.sleep(max(0.0, deadline - time.monotonic()))


def _wait_for_known_subscribers(graph: Graph, publisher: Any, seconds: float) -> None:
    match_known_subscribers(graph, {publisher.topic: publisher}, seconds)


def _match_or_warn(
    graph: Graph, publisher: Any, seconds: float, warn: Callable[[str], None], least: int = 0
) -> None:
    """`match_known_subscribers` for one publisher, warning about what did not match. `least`: wait for
    at least that many matches even when the graph lists fewer."""
    unmatched = match_known_subscribers(graph, {publisher.topic: publisher}, seconds, least)
    if unmatched:
        warn(unmatched_warning(unmatched, seconds))


def match_known_subscribers(
    graph: Graph, publishers: Mapping[str, Any], seconds: float, least: int = 0
) -> list[str]:
    """Wait for the event itself: each publisher (topic -> publisher) has matched every subscriber the
    graph shows on its topic (its matched count), so a volatile subscriber that was there before rostool
    gets the first message too. `seconds` bounds only that wait, counted once the graph has answered: a
    direct ROS 2 listing spends its own discovery time first, and a subscriber it lists still has to
    discover this new publisher (Fast DDS: on its next announcement), so a window that included the
    listing ran out before the match and the message went to nobody. Returns, for each topic where some
    did not match in time, `/topic (node, ...)`, to warn about."""
    if seconds <= 0 or not publishers:
        return []
    try:
        subscribers = {t.name: t.subscribers for t in graph.topics() if t.name in publishers}
    except RostoolError:  # nobody else in the graph (ROS 2: no participant answered in its window)
        return []
    deadline = time.monotonic() + seconds
    unmatched = []
    for topic, publisher in publishers.items():
        known = subscribers.get(topic, [])
        wanted = max(len(known), least)
        matched = not wanted or publisher.wait_for_subscribers(wanted, max(0.0, deadline - time.monotonic()))
        if not matched and known:  # `least` alone is a hope, not a subscriber that is there
            unmatched.append(f"{topic} ({', '.join(known)})")
    return unmatched


def unmatched_warning(unmatched: list[str], seconds: float) -> str:
    """One line naming what never matched (`match_known_subscribers`), and how to change the wait."""
    return (
        f"not every subscriber had matched within {seconds:g} s, publishing anyway: "
        f"{'; '.join(unmatched)} (--match-wait S waits longer, 0 not at all)"
    )


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
    match_wait: float = MATCH_WAIT_SECONDS,
    warn: Callable[[str], None] = lambda _text: None,
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
    else:
        # a volatile subscriber gets nothing published before it matched: wait for the ones the graph
        # knows (every form: the first message of a 1 Hz loop counts too) and, as ros2 topic pub -1/-t
        # does, for at least one (a direct listing may not know of a subscriber yet) unless -w 0 said not to
        least = 1 if plan.total is not None and plan.wait_matching is None else 0
        seconds = match_wait if plan.max_wait is None else min(plan.max_wait, match_wait)
        _match_or_warn(graph, publisher, seconds, warn, least)
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
