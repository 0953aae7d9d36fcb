"""One rclpy context with one node, `/rostool_<pid>`, and an executor spinning it in its own thread.

The context is rostool's own (not rclpy's default) and installs no signal handlers, so Ctrl+C stays
Python's KeyboardInterrupt and the verbs end as with the DDS backend. The node starts no parameter
services, no type description service and no /rosout: it should add as little as possible to the graph it
looks at.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.rclpy.select import WAY_OUT


class RclpyContext:
    def __init__(self, node_name: str) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.context = Context()
        try:
            rclpy.init(args=[], context=self.context, signal_handler_options=SignalHandlerOptions.NO)
            from rclpy.parameter import Parameter

            # no get_type_description service either: it would show in `ros2 service list` as ours
            quiet = [Parameter("start_type_description_service", Parameter.Type.BOOL, False)]
            self.node: Any = rclpy.create_node(
                node_name, context=self.context, start_parameter_services=False, enable_rosout=False,
                parameter_overrides=quiet,
            )  # fmt: skip
            # nor the /parameter_events publisher rclpy gives every node: this one never sets a parameter,
            # and `ros2 topic list -v` beside a long-lived rostool (its graph daemon) would count it
            events = getattr(self.node, "_parameter_event_publisher", None)
            if events is not None:
                self.node.destroy_publisher(events)
        except Exception as err:  # rclpy's RCLError / RMWError: the RMW or its configuration failed
            with contextlib.suppress(Exception):
                self.context.try_shutdown()
            text = " ".join(str(err).split())
            rmw = os.environ.get("RMW_IMPLEMENTATION") or "the default RMW"
            raise RostoolError(f"rclpy cannot start a node with {rmw}: {text}; {WAY_OUT}") from None
        self.name = node_name
        self.full_name = "/" + node_name
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._spin, name="rclpy executor", daemon=True)
        self._thread.start()

    def on_executor(self, function: Callable[[], Any]) -> Any:
        """Run `function` on the executor's thread, between two of its takes; an rclpy Future of its value.
        What sends a request and then registers its reply's future must run there when rclpy takes no lock
        for it (Jazzy's ActionClient): taken in between, the reply is dropped as unexpected."""
        return self.executor.create_task(function)

    def _spin(self) -> None:
        while not self._closed.is_set() and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.1)
            except Exception:  # the context was shut down under the executor: the graph is closing
                if self._closed.is_set() or not self.context.ok():
                    return
                raise

    def close(self) -> None:
        if self._closed.is_set():
            return
        self._closed.set()
        self._thread.join(2.0)
        with contextlib.suppress(Exception):
            self.executor.shutdown(timeout_sec=1.0)
        with contextlib.suppress(Exception):
            self.node.destroy_node()
        with contextlib.suppress(Exception):
            self.context.try_shutdown()
