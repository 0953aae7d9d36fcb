"""A real rclpy node that logs at every level, run with a peer venv's python. Created with
enable_logger_service=True (its `get_logger_levels`/`set_logger_levels` services) unless --no-logger-service.
Every 0.2 s it logs `debug N`, `info N`, `warn N` and `error N` through its node logger (what reaches
/rosout depends on the logger's level). It reports on stdout, as JSON lines:

    {"event": "ready", "node": "/talker", "logger": "talker"}

Not a pytest module: tests start it through tests/test_console.py.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node


class Talker(Node):
    def __init__(self, name: str, logger_service: bool) -> None:
        super().__init__(name, enable_logger_service=logger_service)
        self.count = 0
        self.create_timer(0.2, self.tick)

    def tick(self) -> None:
        self.count += 1
        logger = self.get_logger()
        logger.debug(f"debug {self.count}")
        logger.info(f"info {self.count}")
        logger.warning(f"warn {self.count}")
        logger.error(f"error {self.count}")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--name", default="talker")
    parser.add_argument("--no-logger-service", dest="logger_service", action="store_false")
    args = parser.parse_args()
    rclpy.init()
    node = Talker(args.name, args.logger_service)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    ready = {"event": "ready", "node": node.get_fully_qualified_name(), "logger": node.get_logger().name}
    sys.stdout.write(json.dumps(ready) + "\n")
    sys.stdout.flush()
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        executor.spin()


if __name__ == "__main__":
    main()
