"""The ROS 2 QoS options shared by topic echo/hz/bw/pub and bag record."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import click

from rostool.graph.qos import PROFILE_NAMES, QosRequest

_QOS_OPTIONS = (
    click.option("--qos-profile", type=click.Choice(PROFILE_NAMES),
                 help="ROS 2: QoS preset to start from (echo/hz default: adapt to the publishers)."),
    click.option("--qos-reliability", type=click.Choice(["reliable", "best_effort"]), help="ROS 2 only."),
    click.option("--qos-durability", type=click.Choice(["volatile", "transient_local"]), help="ROS 2 only."),
    click.option("--qos-depth", type=click.IntRange(min=0), help="ROS 2: history depth (0 keeps all)."),
)  # fmt: skip


def qos_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Add the ROS 2 QoS options; the command receives them as one `qos: QosRequest`."""

    @functools.wraps(func)
    def wrapper(
        *args: Any,
        qos_profile: str | None,
        qos_reliability: str | None,
        qos_durability: str | None,
        qos_depth: int | None,
        **kwargs: Any,
    ) -> Any:
        request = QosRequest(qos_profile, qos_reliability, qos_durability, qos_depth)
        return func(*args, qos=request, **kwargs)

    for option in reversed(_QOS_OPTIONS):
        wrapper = option(wrapper)
    return wrapper
