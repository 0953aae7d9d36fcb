"""ros2 node's shared options (`node list`, `node info`): --no-daemon and --spin-time, read by the graph from
the verb's context, and -s/--use-sim-time, which means nothing here."""

from __future__ import annotations

import functools
from typing import Any

import click

from rostool.commands._common import spin_time_option


def ignored_node_options(func: Any) -> Any:
    """ros2cli's node options, kept out of the verb's own arguments."""
    options = (
        click.option("--no-daemon", is_flag=True,
                     help="Ask the ROS 2 graph directly, not its daemon (ROSTOOL_NO_DAEMON=1)."),
        spin_time_option,
        click.option("-s", "--use-sim-time", is_flag=True, help="Accepted and ignored (wall clock)."),
    )  # fmt: skip

    @functools.wraps(func)
    def wrapper(
        *args: Any, no_daemon: bool, spin_time: float | None, use_sim_time: bool, **kwargs: Any
    ) -> Any:
        return func(*args, **kwargs)

    for option in reversed(options):
        wrapper = option(wrapper)
    return wrapper
