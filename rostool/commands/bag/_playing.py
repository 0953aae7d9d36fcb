"""One `bag play` for both forms: rosbag play's flags (play.py) and ros2 bag play's (play_ros2.py) parse into
a `PlayRequest`; `run_play` publishes the bags into the live graph."""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import click

from rostool.bag.play import PlayOptions, PlayResult
from rostool.commands._common import warner
from rostool.errors import RostoolError


@dataclass(frozen=True)
class PlayRequest:
    """What either form asks of the player, however its flags are spelled."""

    bags: Sequence[str]
    distro: str
    options: PlayOptions
    ros2_hz: float  # the /clock rate on a ROS 2 graph
    quiet: bool
    form: Literal["rosbag", "ros2 bag"]  # ros2 bag: a ROS 2 graph only, and only the --topics the bag has
    keyboard: bool  # False: read no keys
    pause_flags: tuple[tuple[str, bool], ...]  # flags given that wait for a key to resume
    nothing_played_hint: str  # which flags to check when no message was played


def run_play(ctx: click.Context, request: PlayRequest) -> PlayResult:
    from rostool.bag.play import Player
    from rostool.bag.play_console import Console
    from rostool.bag.play_ros2 import Ros2Player
    from rostool.bag.play_topics import present_topics
    from rostool.bag.reader import BagReader
    from rostool.commands._common import live_graph

    warn = warner(request.quiet)
    options = request.options
    ros2_form = request.form == "ros2 bag"
    with BagReader(request.bags, request.distro) as reader, live_graph(ctx) as graph:
        console = Console.detect(request.quiet)
        console.form = request.form
        if not request.keyboard:
            console.keyboard = False
        if ros2_form and graph.encoding != "cdr":
            raise RostoolError("the ROS 2 form of bag play needs a ROS 2 graph")
        if ros2_form and options.topics:
            wanted = [graph.resolve(t) for t in options.topics]
            options = dataclasses.replace(options, topics=present_topics(wanted, reader.topics, warn))
        if graph.encoding == "cdr":
            options = dataclasses.replace(options, hz=request.ros2_hz)
            player: Player = Ros2Player(reader, graph, options, console, warn)
        else:
            player = Player(reader, graph, options, console, warn)
        with console:
            player.advertise()
            for flag, used in request.pause_flags:
                if used and not console.keyboard and not player.serves_controls:  # paused forever
                    raise RostoolError(f"{flag} needs a terminal on stdin to resume with space")
            result = player.run()
            if not ros2_form:
                console.say("Done.")
    if result.published == 0 and not request.quiet:
        warn(f"no message was played (check {request.nothing_played_hint})")
    sys.stdout.flush()
    return result
