"""The console script's entry point: Ctrl+C while Python is still importing rostool ends quietly.

Python's default SIGINT handler raises KeyboardInterrupt wherever the import happens to be, which prints a
traceback (or, inside a class body, a RuntimeError from `__set_name__`). Until the root command runs,
nothing has been opened or written, so an interrupt then just exits 130.
"""

from __future__ import annotations

import os
import signal
from types import FrameType


def _interrupted_while_starting(_signum: int, _frame: FrameType | None) -> None:
    os._exit(130)


signal.signal(signal.SIGINT, _interrupted_while_starting)


def _terminated(_signum: int, _frame: FrameType | None) -> None:
    """SIGTERM (`timeout`, `kill`, a supervisor) unwinds like Ctrl+C does, so what the verb opened is
    closed: a ROS 2 participant announces it left instead of lingering in other nodes' view for its lease.
    Verbs with their own meaning for it (bag record, core, the daemon) set their own handler."""
    raise SystemExit(128 + signal.SIGTERM)


def main() -> None:
    from rostool.cli import main as run

    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _terminated)
    run()
