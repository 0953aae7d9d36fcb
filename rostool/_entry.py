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


def main() -> None:
    from rostool.cli import main as run

    signal.signal(signal.SIGINT, signal.default_int_handler)
    run()
