"""ROS 1 graph-name resolution (global, relative and private names)."""

from __future__ import annotations

import os
import random

from rostool.graph.ros1.env import namespace


def resolve(name: str, node_name: str = "/rostool") -> str:
    """Resolve `name` as a command-line tool does: relative names go under ROS_NAMESPACE."""
    if not name:
        return namespace().rstrip("/") or "/"
    if name.startswith("/"):
        resolved = name
    elif name.startswith("~"):
        resolved = node_name.rstrip("/") + "/" + name[1:].lstrip("/")
    else:
        resolved = namespace() + name
    while "//" in resolved:
        resolved = resolved.replace("//", "/")
    return resolved.rstrip("/") if len(resolved) > 1 else resolved


def anonymous(base: str) -> str:
    """A unique node name like rospy's anonymous=True (`/base_<pid>_<millis>`)."""
    suffix = f"{os.getpid()}_{random.randint(0, 10**12):d}"
    return resolve(f"{base.lstrip('/')}_{suffix}")
