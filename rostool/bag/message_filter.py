"""`--filter EXPR` over a bag's messages: a safe expression of the message `m`, its `topic` and time `t`."""

from __future__ import annotations

from collections.abc import Callable

MessageFilter = Callable[[object, str, int], bool]


def message_filter(expr: str | None) -> MessageFilter | None:
    """None keeps every message; else a predicate of (message, topic, receive time in ns)."""
    if expr is None:
        return None
    from rostool.output.filter_expr import Bindings, compile_filter

    predicate = compile_filter(expr, names=("topic", "t"))

    def keep(msg: object, topic: str, timestamp: int) -> bool:
        return predicate(Bindings(msg, {"topic": topic, "t": timestamp / 1e9}))

    return keep
