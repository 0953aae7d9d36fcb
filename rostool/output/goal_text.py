"""What action verbs print: a goal's events as they come (actionlib's YAML blocks, ros2 action send_goal's
text, or one JSON object per event) and actionlib's `action info`."""

from __future__ import annotations

import sys
import threading
from typing import Any

import click

from rostool.output.json_text import dumps
from rostool.output.plain import to_plain
from rostool.output.yaml_text import to_yaml


def action_info_text(found: dict[str, Any], wait: float) -> str:
    """ROS 1 `action info`: type, server, clients and the goals the server tracks."""
    lines = [f"Action: {found['name']}", f"Type: {found['type'] or '?'}"]
    for title, nodes in (("Server", found["servers"]), ("Clients", found["clients"])):
        lines += [f"{title}: {'None' if not nodes else ''}", *(f" * {node}" for node in nodes)]
    goals = found["goals"]
    if goals is None:
        return "\n".join([*lines, f"Goals: unknown (no status from the server within {wait:g} s)"])
    lines.append(f"Goals: {'None' if not goals else ''}")
    for goal in goals:
        lines.append(f" * {goal['id']}: {goal['status']}" + (f" ({goal['text']})" if goal["text"] else ""))
    return "\n".join(lines)


def _print_json(value: Any) -> None:
    click.echo(dumps(value))


class GoalText:
    """Prints goal events: YAML blocks for people, one JSON object per event for scripts."""

    def __init__(self, as_json: bool, show_feedback: bool) -> None:
        self.as_json = as_json
        self.show_feedback = show_feedback

    def waiting(self, text: str) -> None:
        click.echo(text, err=True)

    def canceling(self, goal_id: str) -> None:
        pass  # actionlib's canceling shows in the status events

    def sent(self, goal_id: str, goal: Any = None, accepted: bool = True) -> None:
        if self.as_json:
            _print_json({"event": "sent", "goal_id": goal_id})
        else:
            click.echo(f"Goal sent: {goal_id}")
        sys.stdout.flush()

    def event(self, event: Any) -> None:
        if event.kind == "feedback" and not self.show_feedback:
            return
        if self.as_json:
            body: dict[str, Any] = {"event": event.kind, "status": event.status_name}
            if event.text:
                body["text"] = event.text
            if event.message is not None:
                body[event.kind] = to_plain(event.message)
            _print_json(body)
        elif event.kind == "feedback":
            click.echo("Feedback:\n" + _indented(event.message))
        else:
            text = f" ({event.text})" if event.text else ""
            click.echo(f"Status: {event.status_name}{text}")
            if event.message is not None:
                click.echo("Result:\n" + _indented(event.message))
        sys.stdout.flush()


class Ros2GoalText(GoalText):
    """ros2 action send_goal's text, or one JSON object per event."""

    def __init__(self, as_json: bool, show_feedback: bool) -> None:
        super().__init__(as_json, show_feedback)
        # a feedback can overtake the server's answer to the goal; ros2 prints the answer first
        self.accepted = False
        self.early: list[Any] = []
        self._lock = threading.RLock()

    def sent(self, goal_id: str, goal: Any = None, accepted: bool = True) -> None:
        with self._lock:
            self._sent(goal_id, goal, accepted)

    def _sent(self, goal_id: str, goal: Any, accepted: bool) -> None:
        if not self.waited:  # ros2 prints it even when the server is there at once
            self.waiting("Waiting for an action server to become available...")
        if self.as_json:
            goal_plain = to_plain(goal, "ros2")
            _print_json({"event": "sent", "goal_id": goal_id, "accepted": accepted, "goal": goal_plain})
        else:
            answer = f"Goal accepted with ID: {goal_id}\n" if accepted else "Goal was rejected."
            click.echo(f"Sending goal:\n     {to_yaml(goal, 'ros2')}\n\n{answer}")
        sys.stdout.flush()
        self.accepted = True
        for early in self.early:
            self._event(early)
        self.early.clear()

    waited = False

    def waiting(self, text: str) -> None:
        self.waited = True
        click.echo(text, err=self.as_json)  # ros2 action send_goal prints it first, on stdout
        sys.stdout.flush()

    def canceling(self, goal_id: str) -> None:
        if self.as_json:
            _print_json({"event": "canceling", "goal_id": goal_id})
        else:
            click.echo("Canceling goal...")
        sys.stdout.flush()

    def event(self, event: Any) -> None:
        with self._lock:
            self._event(event)

    def _event(self, event: Any) -> None:
        if event.kind == "feedback" and not self.show_feedback:
            return
        if not self.accepted:
            self.early.append(event)
            return
        if self.as_json:
            body: dict[str, Any] = {"event": event.kind}
            if event.kind == "result":
                body["status"] = event.status_name
            body[event.kind] = to_plain(event.message, "ros2")
            _print_json(body)
        elif event.kind == "feedback":
            click.echo(f"Feedback:\n    {to_yaml(event.message, 'ros2')}\n")
        else:
            click.echo(f"Result:\n    {to_yaml(event.message, 'ros2')}\n")
            click.echo(f"Goal finished with status: {event.status_name}")
        sys.stdout.flush()


def _indented(message: Any) -> str:
    text = to_yaml(message)
    return "\n".join("  " + line for line in text.splitlines()) if text else "  {}"
