"""rosbag2's --qos-profile-overrides-path YAML ({topic: {reliability, durability, depth, ...}}), checked as
ros2 bag checks it and merged into the one QoS rostool's readers use."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest

QOS_KEYS = {
    "history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
    "liveliness_lease_duration", "avoid_ros_namespace_conventions",
}  # fmt: skip


def qos_overrides(path: str | None, apply: bool = True) -> QosRequest | None:
    """The readers' QoS from the file (None: no file, or nothing to apply); `apply=False` only checks it."""
    if path is None:
        return None
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as err:
        raise RostoolError(f"--qos-profile-overrides-path {path}: cannot read it: {err}") from err
    if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
        raise RostoolError(
            f"--qos-profile-overrides-path {path}: expected `/topic: {{reliability: ...}}` entries"
        )
    for topic, entry in data.items():
        unknown = sorted(set(entry) - QOS_KEYS)
        if unknown:
            raise RostoolError(
                f"--qos-profile-overrides-path {path}: {topic}: unknown QoS policy {unknown[0]!r}"
            )
        for key in ("deadline", "lifespan", "liveliness_lease_duration"):
            value = entry.get(key)
            if value is not None and not (isinstance(value, dict) and {"sec", "nsec"} <= value.keys()):
                raise RostoolError(
                    f"--qos-profile-overrides-path {path}: {topic} {key}: "
                    "Time overrides must include both seconds and nanoseconds (sec and nsec)"
                )
    if not apply:  # play: checked only; its publishers offer the QoS the bag recorded
        return None
    return _merged(path, data)


def _merged(path: str, data: dict[str, dict[str, Any]]) -> QosRequest | None:
    merged: dict[str, Any] = {}  # one reader QoS for all: the topics' entries must not contradict
    for entry in data.values():
        for key in ("reliability", "durability", "depth"):
            if key not in entry:
                continue
            value = str(entry[key]).lower() if key != "depth" else entry[key]
            if merged.setdefault(key, value) != value:
                raise RostoolError(
                    f"--qos-profile-overrides-path {path}: rostool applies one QoS to every reader, but the "
                    f"topics ask for different {key}; record them in separate runs"
                )
    if not merged:
        return None
    reliability, durability, depth = (merged.get(k) for k in ("reliability", "durability", "depth"))
    for value, allowed in (
        (reliability, ("reliable", "best_effort")),
        (durability, ("volatile", "transient_local")),
    ):
        if value is not None and value not in allowed:
            raise RostoolError(
                f"--qos-profile-overrides-path {path}: {value!r} is not one of {', '.join(allowed)}"
            )
    return QosRequest(None, reliability, durability, int(depth) if depth is not None else None)
