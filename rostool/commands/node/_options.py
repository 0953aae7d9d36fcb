"""ros2 node's options with no meaning here, shared by `node list` and `node info`."""

from __future__ import annotations

import functools
from typing import Any

import click


def ignored_node_options(func: Any) -> Any:
    """ros2cli's node options with no meaning here: accepted, said so in --help, ignored."""
    options = (
        click.option("--no-daemon", is_flag=True,
                     help="Ask the ROS 2 graph directly, not its daemon (ROSTOOL_NO_DAEMON=1)."),
        click.option("--spin-time", type=float, metavar="S",
                     help="Accepted and ignored (rostool waits for discovery to settle itself)."),
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
