"""A real terminal for the tests of keys and live screens: a tmux session of its own (own server socket),
keys sent with `send-keys`, the screen read with `capture-pane`. Not a pytest module."""

from __future__ import annotations

import itertools
import os
import shlex
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from tests.support import IN_CI

_sessions = itertools.count()


class Terminal:
    """`Terminal(["bag", "play", ...], env, tmp_path)` runs rostool in a 200x50 tmux pane."""

    def __init__(self, args: Sequence[str], env: dict[str, str], cwd: Path, width: int = 200) -> None:
        if shutil.which("tmux") is None:
            if IN_CI:
                pytest.fail("tmux is missing (apt-get install tmux)")
            pytest.skip("tmux is missing (apt-get install tmux)")
        self.socket = f"rostool-test-{os.getpid()}-{next(_sessions)}"
        command = shlex.join([sys.executable, "-m", "rostool", *args])
        # the pane stays after rostool exits, so its last lines and exit status can be read
        shell = f'{command}; echo "[exit $?]"; sleep 600'
        size = ["-x", str(width), "-y", "50"]
        self._tmux("new-session", "-d", "-s", "t", *size, "-c", str(cwd), shell, env=env)

    def _tmux(self, *args: str, env: dict[str, str] | None = None) -> str:
        done = subprocess.run(
            ["tmux", "-L", self.socket, *args], env=env, capture_output=True, text=True, timeout=10
        )
        return done.stdout

    def send(self, *keys: str) -> None:
        """tmux key names: "Space", "Right", "Up", "C-c", or literal text."""
        self._tmux("send-keys", "-t", "t", *keys)

    def screen(self) -> str:
        """Everything the pane shows and scrolled past, wrapped lines joined."""
        return self._tmux("capture-pane", "-p", "-J", "-t", "t", "-S", "-500")

    def wait_for(self, predicate: Callable[[str], bool], timeout: float = 20.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate(self.screen()):
                return True
            time.sleep(0.05)
        return predicate(self.screen())

    def close(self) -> None:
        self._tmux("kill-server")
