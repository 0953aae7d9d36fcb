"""The console script's entry point: Ctrl+C while Python is still importing rostool ends quietly, and a
finished verb ends without the interpreter's finalization.

Python's default SIGINT handler raises KeyboardInterrupt wherever the import happens to be, which prints a
traceback (or, inside a class body, a RuntimeError from `__set_name__`). Until the root command runs,
nothing has been opened or written, so an interrupt then just exits 130.
"""

from __future__ import annotations

import os
import signal
import sys
from types import FrameType
from typing import NoReturn


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
    try:
        run()
        code = 0
    except SystemExit as done:
        code = _exit_code(done.code)
    _end(code)


def _exit_code(code: object) -> int:
    """The status `sys.exit(code)` would end with (a message is printed and ends with 1, as Python does)."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1


def _end(code: int) -> NoReturn:
    """End as a normal exit would, without the interpreter's finalization (tearing down every module and
    object: 0.01-0.03 s per call on an idle machine, 0.1 s under load; bench/bench_exit.py). The verb has
    returned, so what it opened is closed (bag writers, exports, graph endpoints: each verb closes its
    own, as it must on Ctrl+C too); what a normal exit still does comes first: non-daemon threads joined,
    atexit handlers run (the libraries' too), Python's and C's buffered output flushed."""
    import atexit
    import contextlib
    import threading

    try:
        join_threads = getattr(threading, "_shutdown", None)  # what Py_Finalize calls first
        if join_threads is not None:
            join_threads()
        atexit._run_exitfuncs()
    except KeyboardInterrupt:
        code = 130
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):  # a closed pipe (`| head`) ends quietly, as cli.py does
            stream.flush()
    if "ctypes" in sys.modules:  # a C library's stdio buffers (rcl's, Cyclone's) are flushed by exit()
        with contextlib.suppress(Exception):
            sys.modules["ctypes"].CDLL(None).fflush(None)
    os._exit(code)
