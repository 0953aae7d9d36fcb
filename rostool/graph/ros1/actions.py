"""actionlib over topics: find action servers, send a goal, follow its feedback and result, cancel.

An action NS is five topics: NS/goal and NS/cancel (clients publish, the server subscribes), NS/status,
NS/feedback and NS/result (the server publishes). A goal carries a GoalID that the status, feedback and
result messages repeat, so several clients can share one server.
"""

from __future__ import annotations

import itertools
import os
import queue
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError
from rostool.graph.base import ActionSummary, GoalEvent, GoalOutcome
from rostool.graph.ros1.names import resolve
from rostool.interfaces.action import (
    SUCCEEDED,
    TERMINAL_STATUSES,
    ActionType,
    action_type_name,
    load_action,
    status_name,
)

if TYPE_CHECKING:
    from rostool.graph.ros1.core import Ros1Core
    from rostool.graph.ros1.topics import InboundLink, Subscription
    from rostool.interfaces.ros1 import Ros1Type
    from rostool.interfaces.sources import Interfaces

ACTION_TOPICS = ("goal", "cancel", "status", "feedback", "result")
CANCEL_WAIT = 3.0  # after a cancel, how long to wait for the server to confirm
STATUS_SILENCE = 5.0  # no status for this long while a goal runs: the server is gone
WAIT_NOTICE = 2.0  # say that we are waiting for the server after this long
_goal_numbers = itertools.count(1)


@dataclass(frozen=True)
class GoalState:
    """A goal as the server's status topic lists it, with actionlib's name of its status."""

    id: str
    status: str
    text: str


def _event(kind: str, status: int, text: str = "", message: Any = None) -> GoalEvent:
    """A goal's feedback, status change or result, its status named as actionlib names it."""
    return GoalEvent(kind, status, status_name(status), message, text)


class GoalTimeout(RostoolError):
    pass


def list_actions(graph: Ros1Core) -> list[ActionSummary]:
    """Every namespace that has all five action topics, with its type, servers and clients."""
    publishers, subscribers, _services = graph.master.system_state()
    pubs = {str(t): sorted(nodes) for t, nodes in publishers}
    subs = {str(t): sorted(nodes) for t, nodes in subscribers}
    topics = set(pubs) | set(subs)
    types = graph.master.topic_types()
    found = []
    for topic in sorted(topics):
        ns = topic[: -len("/goal")]
        if topic.endswith("/goal") and all(f"{ns}/{part}" in topics for part in ACTION_TOPICS):
            found.append(_summary(ns, pubs, subs, types))
    return found


def _summary(
    ns: str, pubs: dict[str, list[str]], subs: dict[str, list[str]], types: dict[str, str]
) -> ActionSummary:
    servers = sorted(set(pubs.get(f"{ns}/status", [])) | set(pubs.get(f"{ns}/result", [])))
    clients = sorted((set(pubs.get(f"{ns}/goal", [])) | set(subs.get(f"{ns}/result", []))) - set(servers))
    return ActionSummary(ns, _type_from_topics(ns, types), servers, clients)


def _type_from_topics(ns: str, types: dict[str, str]) -> str | None:
    for part, suffix in (("goal", "ActionGoal"), ("result", "ActionResult"), ("feedback", "ActionFeedback")):
        topic_type = types.get(f"{ns}/{part}", "")
        if topic_type.endswith(suffix) and len(topic_type) > len(suffix):
            return topic_type[: -len(suffix)]
    return None


def action_summary(graph: Ros1Core, name: str) -> ActionSummary:
    ns = resolve(name)
    for summary in list_actions(graph):
        if summary.name == ns:
            return summary
    raise RostoolError(f"no action {ns}: it needs the topics {ns}/{{goal,cancel,status,feedback,result}} "
                       "(see `rostool action list`)")  # fmt: skip


def goal_states(graph: Ros1Core, name: str, wait: float = 2.0) -> list[GoalState] | None:
    """The goals the server reports on NS/status (None when no status arrives within `wait`)."""
    arrived: queue.Queue[bytes] = queue.Queue()
    status_type = graph.types.builtin("actionlib_msgs/GoalStatusArray")
    graph.node.subscribe(f"{resolve(name)}/status", lambda payload, _link: arrived.put(payload), status_type)
    try:
        payload = arrived.get(timeout=wait)
    except queue.Empty:
        return None
    message = status_type.deserialize(payload)
    return [GoalState(s.goal_id.id, status_name(int(s.status)), s.text) for s in message.status_list]


def resolve_action_type(graph: Ros1Core, catalog: Interfaces, name: str, type_name: str | None) -> ActionType:
    """The action type given, or the one the master knows for NS/goal (pkg/XActionGoal -> pkg/X)."""
    ns = resolve(name)
    _publishers, subscribers, _services = graph.master.system_state()
    # rosmaster keeps a topic's type after everyone left, so only a listening server's type counts
    serving = any(topic == f"{ns}/goal" and nodes for topic, nodes in subscribers)
    known = _type_from_topics(ns, graph.master.topic_types()) if serving else None
    if type_name is None:
        if known is None:
            raise RostoolError(
                f"the type of action {ns} is unknown: no server listens on {ns}/goal. Start the server, "
                "or give the type, e.g. `rostool action send-goal /fibonacci actionlib/TwoInts ...`"
            )
        type_name = known
    wanted = action_type_name(type_name, catalog)
    if known is not None and known != wanted:
        raise RostoolError(f"action {ns} has type {known}, not {wanted}")
    return load_action(catalog, wanted)


def new_goal_id(now_ns: int | None = None) -> str:
    """A unique goal id in actionlib's form: NAME-COUNT-SECS.NSECS."""
    now_ns = time.time_ns() if now_ns is None else now_ns
    return f"/rostool-{os.getpid()}-{next(_goal_numbers)}-{now_ns // 10**9}.{now_ns % 10**9}"


class ActionClient:
    """One client of one action server, with the five topics set up on the graph's node."""

    def __init__(self, graph: Ros1Core, name: str, action: ActionType) -> None:
        self.ns = resolve(name)
        self.action = action
        self.graph = graph
        node = graph.node
        self.goal_id = ""
        self._events: queue.Queue[GoalEvent] = queue.Queue()
        self._status_seen = threading.Event()
        self._last_status_at = 0.0
        self._last_status: int | None = None
        self._lock = threading.Lock()
        status_type = graph.types.builtin("actionlib_msgs/GoalStatusArray")
        self._cancel_type = graph.types.builtin("actionlib_msgs/GoalID")
        self._goal_pub = node.advertise(f"{self.ns}/goal", action.action_goal)
        self._cancel_pub = node.advertise(f"{self.ns}/cancel", self._cancel_type)
        self._status_sub = node.subscribe(f"{self.ns}/status", self._on_status, status_type)
        self._feedback_sub = node.subscribe(
            f"{self.ns}/feedback", self._decoding(action.action_feedback, self._on_feedback), None
        )
        self._result_sub = node.subscribe(
            f"{self.ns}/result", self._decoding(action.action_result, self._on_result), None
        )

    # --- setup --------------------------------------------------------------------------------
    def _decoding(
        self, expected: Ros1Type, deliver: Callable[[Any], None]
    ) -> Callable[[bytes, InboundLink], None]:
        """Decode with our type when the md5 matches, else with the definition the server sent."""
        registry = self.graph.types

        def on_payload(payload: bytes, link: InboundLink) -> None:
            try:
                ours = link.header.get("md5sum", "*") == expected.md5sum
                msg_type = expected if ours else registry.from_header(link.header)
                message = msg_type.deserialize(payload)
            except Exception:  # a message we cannot read must not end the connection thread
                return
            deliver(message)

        return on_payload

    def wait_for_server(self, timeout: float | None, on_waiting: Callable[[str], None] | None = None) -> None:
        """Until the server listens to our goal and cancel topics and we hear its status and results."""
        started = time.monotonic()
        deadline = None if timeout is None else started + timeout
        told = on_waiting is None
        _pubs, subs, _srvs = self.graph.master.system_state()
        goal_listeners = max(1, len(next((n for t, n in subs if t == f"{self.ns}/goal"), [])))
        while True:
            if (
                self._status_seen.is_set()
                and self._goal_pub.subscriber_count >= goal_listeners
                and self._cancel_pub.subscriber_count >= 1
                and _connected(self._result_sub)
                and _connected(self._feedback_sub)
            ):
                return
            if not told and time.monotonic() - started > WAIT_NOTICE:
                told = True
                assert on_waiting is not None
                on_waiting(f"waiting for the action server of {self.ns}...")
            if deadline is not None and time.monotonic() >= deadline:
                raise GoalTimeout(f"the action server of {self.ns} did not connect within {timeout:g} s "
                                  "(is it running? see `rostool action list`)")  # fmt: skip
            time.sleep(0.02)

    # --- callbacks (TCPROS reader threads) ------------------------------------------------------
    def _on_status(self, payload: bytes, _link: InboundLink) -> None:
        self._last_status_at = time.monotonic()
        self._status_seen.set()
        if not self.goal_id:
            return
        try:
            message = self.graph.types.builtin("actionlib_msgs/GoalStatusArray").deserialize(payload)
        except Exception:  # a message we cannot read must not end the connection thread
            return
        for status in message.status_list:
            if status.goal_id.id == self.goal_id:
                code = int(status.status)
                with self._lock:
                    changed, self._last_status = code != self._last_status, code
                if changed:
                    self._events.put(_event("status", code, status.text))

    def _on_feedback(self, message: Any) -> None:
        if self.goal_id and message.status.goal_id.id == self.goal_id:
            self._events.put(_event("feedback", int(message.status.status), message.status.text,
                                    message.feedback))  # fmt: skip

    def _on_result(self, message: Any) -> None:
        if self.goal_id and message.status.goal_id.id == self.goal_id:
            self._events.put(
                _event("result", int(message.status.status), message.status.text, message.result)
            )

    # --- goals ----------------------------------------------------------------------------------
    def build_goal(self, value: Any, goal_id: str = "", now_ns: int | None = None) -> Any:
        """The ActionGoal message for a goal given as YAML values (checked before anything is sent)."""
        from rostool.interfaces.fill import build_message

        now_ns = time.time_ns() if now_ns is None else now_ns
        stamp = {"secs": now_ns // 10**9, "nsecs": now_ns % 10**9}
        wrapper = {"header": {"stamp": stamp}, "goal_id": {"stamp": stamp, "id": goal_id}, "goal": value}
        goal_type = self.action.action_goal
        return build_message(goal_type.store, goal_type.store_name, wrapper)

    def send_goal(self, value: Any) -> str:
        now_ns = time.time_ns()
        self.goal_id = new_goal_id(now_ns)
        self._goal_pub.publish(self.build_goal(value, self.goal_id, now_ns))
        return self.goal_id

    def cancel(self, goal_id: str | None = None) -> None:
        """Cancel one goal (ours by default), or every goal with goal_id=''."""
        from rostool.interfaces.fill import build_message

        target = self.goal_id if goal_id is None else goal_id
        store = self._cancel_type.store
        self._cancel_pub.publish(build_message(store, self._cancel_type.store_name, {"id": target}))

    def events(self, timeout: float | None = None) -> Iterator[GoalEvent]:
        """Status changes and feedback of our goal, ending with its result."""
        deadline = None if timeout is None else time.monotonic() + timeout
        self._last_status_at = time.monotonic()
        while True:
            wait = 0.1 if deadline is None else min(0.1, deadline - time.monotonic())
            if wait <= 0:
                raise GoalTimeout(f"goal {self.goal_id} got no result within {timeout:g} s")
            try:
                event = self._events.get(timeout=wait)
            except queue.Empty:
                if time.monotonic() - self._last_status_at > STATUS_SILENCE:
                    raise RostoolError(f"the action server of {self.ns} stopped publishing its status "
                                       "(did it exit?)") from None  # fmt: skip
                continue
            yield event
            if event.kind == "result":
                return

    def outcome_after_cancel(self, wait: float = CANCEL_WAIT) -> GoalEvent | None:
        """The result the server sends once it has handled our cancel (None if it does not in time)."""
        deadline = time.monotonic() + wait
        last: GoalEvent | None = None
        while (remaining := deadline - time.monotonic()) > 0:
            try:
                event = self._events.get(timeout=remaining)
            except queue.Empty:
                break
            if event.kind == "result":
                return event
            if event.kind == "status" and event.status in TERMINAL_STATUSES:
                last = event
        return last


def _connected(subscription: Subscription) -> bool:
    links = subscription.links()
    return not links or any(link.connected for link in links)


def send_goal(
    graph: Ros1Core,
    catalog: Interfaces,
    name: str,
    type_name: str | None,
    value: Any,
    timeout: float | None = None,
    on_event: Callable[[GoalEvent], None] | None = None,
    on_sent: Callable[[str], None] | None = None,
    on_waiting: Callable[[str], None] | None = None,
) -> GoalOutcome:
    """Send one goal and follow it to its result. On timeout or Ctrl+C the goal is canceled first."""
    action = resolve_action_type(graph, catalog, name, type_name)
    client = ActionClient(graph, name, action)
    client.build_goal(value)  # bad values fail here, before anything is sent
    started = time.monotonic()
    client.wait_for_server(timeout, on_waiting)
    goal_id = client.send_goal(value)
    if on_sent is not None:
        on_sent(goal_id)
    remaining = None if timeout is None else max(0.01, timeout - (time.monotonic() - started))
    try:
        for event in client.events(remaining):
            if on_event is not None and event.kind != "status":
                on_event(event)
            if event.kind == "result":
                return GoalOutcome(goal_id, event.status, event.message, event.text,
                                   succeeded=event.status == SUCCEEDED)  # fmt: skip
    except (KeyboardInterrupt, GoalTimeout) as stop:
        client.cancel()
        final = client.outcome_after_cancel()
        if final is not None and on_event is not None:
            on_event(_event("result", final.status, final.text, final.message))
        if isinstance(stop, GoalTimeout):
            status = f"; the server reports {final.status_name}" if final is not None else ""
            raise GoalTimeout(
                f"goal {goal_id} got no result within {timeout:g} s; canceled it{status}"
            ) from None
        raise
    raise RostoolError(f"goal {goal_id} ended without a result")


def cancel_goals(graph: Ros1Core, name: str, goal_id: str, wait: float = 3.0) -> int:
    """Publish one cancel on NS/cancel (goal_id '' cancels every goal); returns the listeners reached."""
    from rostool.interfaces.fill import build_message

    ns = resolve(name)
    cancel_type = graph.types.builtin("actionlib_msgs/GoalID")
    _pubs, subs, _srvs = graph.master.system_state()
    listeners = len(next((n for t, n in subs if t == f"{ns}/cancel"), []))
    if listeners == 0:
        raise RostoolError(f"nothing listens on {ns}/cancel: no action server runs at {ns}")
    publisher = graph.node.advertise(f"{ns}/cancel", cancel_type)
    publisher.wait_for_subscribers(listeners, wait)
    reached = publisher.subscriber_count
    if reached == 0:
        raise RostoolError(f"the action server of {ns} did not connect to our cancel topic within {wait:g} s")
    publisher.publish(build_message(cancel_type.store, cancel_type.store_name, {"id": goal_id}))
    time.sleep(0.2)  # let the message leave before the node unregisters
    return reached
