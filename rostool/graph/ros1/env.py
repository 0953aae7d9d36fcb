"""ROS 1 environment: ROS_MASTER_URI, ROS_HOSTNAME, ROS_IP, ROS_NAMESPACE, and the address rostool's nodes
give the master for other nodes to call back."""

from __future__ import annotations

import functools
import os
import socket
import sys
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


def is_loopback(host: str) -> bool:
    """Whether `host` (a name or a literal address) is loopback."""
    return host in ("localhost", "::1") or host.startswith("127.")


def pinned_host() -> tuple[str, str] | None:
    """(variable, value) of the name or address the user gave for this machine: ROS_HOSTNAME, else ROS_IP."""
    for var in ("ROS_HOSTNAME", "ROS_IP"):
        value = os.environ.get(var, "").strip()
        if value:
            return var, value
    return None


def advertised_host() -> str:
    """The host name peers use to reach us: ROS_HOSTNAME, else ROS_IP; else 127.0.0.1 for a master on
    loopback; else this machine's name, as rospy does, unless that name cannot take other machines back
    here (it resolves to loopback, as Debian's default /etc/hosts makes it, or not at all): then the source
    address of this machine's route to the master (what `ip route get <master>` says), said once on stderr."""
    pinned = pinned_host()
    if pinned is not None:
        return pinned[1]
    master_host = urlparse(master_uri()).hostname or "localhost"
    if is_loopback(master_host):
        return "127.0.0.1"
    port = urlparse(master_uri()).port or MASTER_PORT
    return _name_for_remote_master(master_host, port, f"the master at {master_host}", "the master")


def resolve(host: str) -> str | None:
    """The first IPv4 (else IPv6) address `host` resolves to here, or None."""
    try:
        infos = socket.getaddrinfo(host, None, proto=socket.IPPROTO_TCP)
    except (OSError, UnicodeError):
        return None
    infos.sort(key=lambda info: info[0] != socket.AF_INET)
    return str(infos[0][4][0]) if infos else None


def route_source(host: str, port: int = MASTER_PORT) -> str | None:
    """This machine's address on its route to `host` (the kernel's choice, as `ip route get` shows it): a
    UDP socket connected there, which sends nothing. None when `host` does not resolve or has no route."""
    address = resolve(host)
    if address is None:
        return None
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    try:
        with socket.socket(family, socket.SOCK_DGRAM) as probe:
            probe.connect((address, port))
            return str(probe.getsockname()[0])
    except OSError:
        return None


def loopback_name(name: str) -> str | None:
    """Why other machines cannot reach this machine by `name` ("resolves to 127.0.1.1", "does not
    resolve"), or None when it resolves to an address of a network."""
    address = resolve(name)
    if address is None:
        return "does not resolve here"
    if is_loopback(address):
        return f"resolves to {address}"
    return None


def served_name() -> str:
    """The name a server listening on every interface (`rostool core --host 0.0.0.0`) advertises:
    ROS_HOSTNAME, ROS_IP, else this machine's name, or when that name cannot take other machines back here,
    the source address of its default route (said once on stderr)."""
    pinned = pinned_host()
    if pinned is not None:
        return pinned[1]
    # 192.0.2.1 (TEST-NET-1) is never on a route of its own: the kernel answers with the default route
    return _name_for_remote_master("192.0.2.1", MASTER_PORT, "other machines", "them")


@functools.cache
def _name_for_remote_master(master_host: str, master_port: int, whom: str, route_to: str) -> str:
    """This machine's name, or when other machines cannot reach it by that name, the source address of its
    route to `master_host`, said once (to `whom`, on the route to `route_to`)."""
    name = socket.gethostname()
    why = loopback_name(name)
    if why is None:
        return name
    address = route_source(master_host, master_port)
    if address is None or is_loopback(address):
        return name  # the master itself is on this machine (or unreachable): nothing better to offer
    sys.stderr.write(
        f"rostool: advertising {address} to {whom} for other nodes to call back: this machine's name "
        f"{name!r} {why}, which they cannot reach ({address} is this machine's address on its route to "
        f"{route_to}); set ROS_IP={address} to pin it, or ROS_IP/ROS_HOSTNAME to choose another\n"
    )
    return address


def bind_host() -> str:
    """Bind loopback when we advertise a loopback name (as rospy does), all interfaces otherwise."""
    host = advertised_host()
    if is_loopback(host):
        return "127.0.0.1" if host == "localhost" else host
    return "0.0.0.0"


def namespace() -> str:
    value = os.environ.get("ROS_NAMESPACE", "/").strip() or "/"
    if not value.startswith("/"):
        value = "/" + value
    return value if value.endswith("/") else value + "/"
