"""The terminal side of `bag play`: rosbag's status line on stderr and the keys on stdin (space, s, t, and
rosbag2's arrows: right plays the next message, up/down change the rate)."""

from __future__ import annotations

import contextlib
import os
import select
import sys
from typing import Any, Literal, TextIO

# Cursor keys as terminals send them (normal and application mode); other keys are their character.
_ARROWS = {"\x1b[A": "UP", "\x1b[B": "DOWN", "\x1b[C": "RIGHT", "\x1b[D": "LEFT",
           "\x1bOA": "UP", "\x1bOB": "DOWN", "\x1bOC": "RIGHT", "\x1bOD": "LEFT"}  # fmt: skip


def split_keys(text: str) -> list[str]:
    """The keys in what the terminal sent: "UP", "DOWN", "RIGHT", "LEFT" or one character each."""
    keys = []
    i = 0
    while i < len(text):
        arrow = _ARROWS.get(text[i : i + 3])
        keys.append(arrow or text[i])
        i += 3 if arrow else 1
    return keys


class Console:
    """The terminal side of playback: rosbag's status line on stderr and space/s keys on stdin.

    The status line needs stderr to be a terminal; the keys need stdin to be the controlling terminal of a
    foreground process (else changing its mode would stop us with SIGTTOU). Terminal settings are always
    restored, Ctrl+C included."""

    def __init__(self, status: bool, keyboard: bool, err: TextIO | None = None) -> None:
        self.err = err or sys.stderr
        self.show_status = status
        self.keyboard = keyboard
        self._saved: Any = None
        self._fd = -1
        self._shown = False
        self.form: Literal["rosbag", "ros2 bag"] = "rosbag"  # whose help and log lines to print

    @classmethod
    def detect(cls, quiet: bool) -> Console:
        status = not quiet and sys.stderr.isatty()
        keyboard = False
        with contextlib.suppress(OSError, ValueError, AttributeError):
            fd = sys.stdin.fileno()
            keyboard = os.isatty(fd) and os.tcgetpgrp(fd) == os.getpgrp()
        return cls(status, keyboard)

    def __enter__(self) -> Console:
        if self.keyboard:
            import termios
            import tty

            try:
                self._fd = sys.stdin.fileno()
                self._saved = termios.tcgetattr(self._fd)
                tty.setcbreak(self._fd)
            except (OSError, termios.error):
                self.keyboard = False
        return self

    def __exit__(self, *_exc: object) -> None:
        if self._saved is not None:
            import termios

            with contextlib.suppress(OSError, termios.error):
                termios.tcsetattr(self._fd, termios.TCSADRAIN, self._saved)
            self._saved = None
        if self._shown:
            self.err.write("\n")
            self.err.flush()
            self._shown = False

    def read_keys(self) -> str:
        if not self.keyboard:
            return ""
        ready, _w, _x = select.select([self._fd], [], [], 0)
        if not ready:
            return ""
        return os.read(self._fd, 64).decode(errors="replace")

    def status(self, state: str, bag_time: float, elapsed: float, total: float, rate: float = 1.0) -> None:
        if not self.show_status:
            return
        line = f" [{state}]  Bag Time: {bag_time:13.6f}   Duration: {elapsed:.6f} / {total:.6f}"
        if rate != 1.0:  # rosbag's line is unchanged at its default rate
            line += f"   Rate: {rate:.3g}"
        self.err.write(f"\r{line}               \r")
        self.err.flush()
        self._shown = True

    def say(self, text: str) -> None:
        if self.show_status:
            if self._shown:
                self.err.write("\n")
                self._shown = False
            self.err.write(text + "\n")
            self.err.flush()
