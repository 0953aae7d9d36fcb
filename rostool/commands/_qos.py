"""The ROS 2 QoS options shared by topic echo/hz/bw/pub and bag record; echo and pub also take ros2 topic's
history and liveliness options."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import click

from rostool.graph.qos import (
    DURABILITY_NAMES,
    HISTORY_NAMES,
    LIVELINESS_NAMES,
    PROFILE_NAMES,
    RELIABILITY_NAMES,
    QosRequest,
)

_QOS_OPTIONS = (
    click.option("--qos-profile", type=click.Choice(PROFILE_NAMES),
                 help="ROS 2: QoS preset to start from (echo/hz default: adapt to the publishers)."),
    click.option("--qos-reliability", type=click.Choice(RELIABILITY_NAMES), help="ROS 2 only."),
    click.option("--qos-durability", type=click.Choice(DURABILITY_NAMES), help="ROS 2 only."),
    click.option("--qos-depth", type=click.IntRange(min=0), help="ROS 2: history depth (0 keeps all)."),
)  # fmt: skip
_TOPIC_QOS_OPTIONS = (
    click.option("--qos-history", type=click.Choice(HISTORY_NAMES),
                 help="ROS 2: keep_last (--qos-depth messages), keep_all or the middleware's default."),
    click.option("--qos-liveliness", type=click.Choice(LIVELINESS_NAMES),
                 help="ROS 2: how a publisher shows it is alive (subscriptions: the least they accept)."),
    click.option("--qos-liveliness-lease-duration-seconds", "qos_lease", type=float, metavar="S",
                 help="ROS 2: liveliness lease in seconds (0 or less: not set, i.e. infinite)."),
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
        qos_history: str | None = None,
        qos_liveliness: str | None = None,
        qos_lease: float | None = None,
        **kwargs: Any,
    ) -> Any:
        request = QosRequest(
            qos_profile, qos_reliability, qos_durability, qos_depth, qos_history, qos_liveliness, qos_lease
        )
        return func(*args, qos=request, **kwargs)

    for option in reversed(_QOS_OPTIONS):
        wrapper = option(wrapper)
    return wrapper


def topic_qos_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """qos_options with ros2 topic echo/pub's --qos-history, --qos-liveliness and
    --qos-liveliness-lease-duration-seconds."""
    wrapper = qos_options(func)
    for option in reversed(_TOPIC_QOS_OPTIONS):
        wrapper = option(wrapper)
    return wrapper
