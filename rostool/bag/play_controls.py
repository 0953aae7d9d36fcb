"""The player's side of control requests: rosbag2's control services (player_services.py), done the way the
keys do them (play.py `Player._ui` hands them to `PlayControls._command` between two waits)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rostool.bag.schedule import PlayClock

if TYPE_CHECKING:
    from rostool.bag.player_services import Command, Controls
    from rostool.bag.reader import BagReader


@dataclass
class Burst:
    """Messages to publish at once while paused (the right arrow: one; rosbag2's burst and play_next)."""

    left: int | None  # None: the rest of the bag
    command: Command | None = None  # the service request to answer when done
    done: int = 0

    def sent(self) -> bool:
        """One more was published; True when that was the last."""
        self.done += 1
        if self.left is not None:
            self.left -= 1
        return self.left == 0

    def reply(self) -> None:
        if self.command is not None:
            if self.command.name == "play_next":
                self.command.reply(success=self.done > 0)
            else:
                self.command.reply(actually_burst=self.done)


class PlayControls:
    """Pause, resume, rate, next message, burst, seek and stop for the player's loop (play.py reads
    `_burst`, `_seek_to` and `_stopping` between messages)."""

    clock: PlayClock
    reader: BagReader
    window: tuple[int, int | None]
    warn: Callable[[str], None]
    _burst: Burst | None = None
    _seek_to: int | None = None  # bag time to continue from (rosbag2's seek)
    _stopping = False  # rosbag2's stop: end playing
    controls: Controls | None = None  # rosbag2's control services (play_ros2)

    def _commands(self, now: float) -> None:
        """Do what the services asked since the last look."""
        if self.controls is not None:
            for command in self.controls.pending():
                self._command(command, now)

    @property
    def serves_controls(self) -> bool:
        """Whether control services (resume, ...) are served: playing can then resume without keys."""
        return False

    def close_controls(self) -> None:
        """Answer what the services still ask: playing has ended."""
        if self._burst is not None:
            self._burst.reply()
            self._burst = None
        if self.controls is not None:
            self.controls.close()

    def _command(self, command: Command, now: float) -> None:
        """A request of rosbag2's control services (player_services.py), done as the keys do it."""
        clock, name, value = self.clock, command.name, command.value
        if name in ("pause", "resume", "toggle_paused"):
            if name == "pause" or (name == "toggle_paused" and not clock.paused):
                clock.pause(now)
            else:
                clock.resume(now)
            command.reply()
        elif name == "is_paused":
            command.reply(paused=clock.paused)
        elif name == "get_rate":
            command.reply(rate=clock.rate)
        elif name == "set_rate":
            if value > 0:
                clock.set_rate(value, now)
            command.reply(success=value > 0)
        elif name in ("play_next", "burst"):
            if not clock.paused or self._burst is not None:  # rosbag2: only while paused
                self.warn(f"{name} is done only while paused")
                command.reply(**({"success": False} if name == "play_next" else {"actually_burst": 0}))
            else:
                self._burst = Burst(1 if name == "play_next" else value or None, command)
        elif name == "seek":
            start, end = self.window
            last = self.reader.end_ns if end is None else end
            if value > last:
                command.reply(success=False)
            else:
                self._seek_to = max(value, start)
                command.reply(success=True)
        elif name == "stop":
            self._stopping = True
            command.reply()
