"""A real rclpy LifecycleNode (as ros2cli's simple_lifecycle_node fixture), run with a peer venv's python.
Every transition succeeds; the node reports on stdout, as JSON lines:

    {"event": "ready", "node": "/test_lifecycle_node"}   once its lifecycle services exist
    {"event": "state", "label": "inactive", "id": 2}      after each transition, from its own state machine

Not a pytest module: tests start it through tests/test_lifecycle.py (the launcher of tests/ros2_peers.py's
environment).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn


def emit(event: str, **fields: object) -> None:
    sys.stdout.write(json.dumps({"event": event, **fields}) + "\n")
    sys.stdout.flush()


class ReportingLifecycleNode(LifecycleNode):
    """Reports the state its state machine entered once each transition's callback has returned."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        # rclpy runs the callback, then the state machine moves on: report from the timer after it settled
        self.reported = self.current_state()
        self.create_timer(0.05, self.report)

    def current_state(self) -> tuple[int, str]:
        return self._state_machine.current_state

    def report(self) -> None:
        state = self.current_state()
        if state != self.reported:
            self.reported = state
            emit("state", id=state[0], label=state[1])

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        return TransitionCallbackReturn.SUCCESS


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--name", default="test_lifecycle_node")
    args = parser.parse_args()
    rclpy.init()
    node = ReportingLifecycleNode(args.name)
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    emit("ready", node=node.get_fully_qualified_name())
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        executor.spin()


if __name__ == "__main__":
    main()
