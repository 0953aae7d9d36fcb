"""ROS 1 environment: ROS_MASTER_URI, ROS_HOSTNAME, ROS_IP, ROS_NAMESPACE."""

from __future__ import annotations

import os
import socket
from urllib.parse import urlparse

from rostool.errors import RostoolError

MASTER_PORT = 11311
MASTER_HOST = "127.0.0.1"  # where rostool's embedded master listens unless told: this machine only
DEFAULT_MASTER_URI = f"http://localhost:{MASTER_PORT}"


def master_uri() -> str:
    uri = os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI
    try:
        parsed = urlparse(uri)
        valid = parsed.scheme in ("http", "https") and bool(parsed.hostname) and parsed.port is not None
    except ValueError:
        valid = False
    if not valid:
        raise RostoolError(f"ROS_MASTER_URI={uri!r} is not a master URI like http://localhost:11311")
    return uri


def _is_loopback(host: str) -> bool:
    return host in ("localhost", "::1") or host.startswith("127.")


def advertised_host() -> str:
    """The host name peers use to reach us (ROS_HOSTNAME, else ROS_IP, else as rospy decides)."""
    for var in ("ROS_HOSTNAME", "ROS_IP"):
        value = os.environ.get(var, "").strip()
        if value:
            return value
    master_host = urlparse(master_uri()).hostname or "localhost"
    if _is_loopback(master_host):
        return "127.0.0.1"
    return socket.gethostname()


def bind_host() -> str:
    """Bind loopback when we advertise a loopback name (as rospy does), all interfaces otherwise."""
    host = advertised_host()
    if _is_loopback(host):
        return "127.0.0.1" if host == "localhost" else host
    return "0.0.0.0"


def namespace() -> str:
    value = os.environ.get("ROS_NAMESPACE", "/").strip() or "/"
    if not value.startswith("/"):
        value = "/" + value
    return value if value.endswith("/") else value + "/"
