"""One JSON object per message, for scripts (jq-friendly: no NaN literals)."""

from __future__ import annotations

import json
import math
from typing import Any

from rostool.output.plain import TimeStyle, to_plain


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, bytes):  # a byte of a ROS 2 byte array parameter
        return value[0] if len(value) == 1 else list(value)
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def dumps(value: Any) -> str:
    """JSON for plain values; non-finite floats become the strings "NaN", "Infinity", "-Infinity"."""
    try:
        return json.dumps(value, allow_nan=False, ensure_ascii=False)
    except (ValueError, TypeError):
        return json.dumps(_finite(value), ensure_ascii=False)


def to_json(msg: object, style: TimeStyle = "ros1") -> str:
    return dumps(to_plain(msg, style))
