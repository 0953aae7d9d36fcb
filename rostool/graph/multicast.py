"""UDP multicast sockets on ros2's group and port (`rostool multicast`, `rostool doctor hello`): a socket that
sends on the interface of the group's route, and one that joined the group. Only the standard library."""

from __future__ import annotations

import socket
import struct

from rostool.errors import RostoolError

GROUP = "225.0.0.1"
PORT = 49150
ROUTE_HINT = "is there a route for multicast (a default route or `ip route add 224.0.0.0/4 dev IFACE`)?"


def outgoing_address(group: str) -> str:
    """The local address the routing table picks for `group` (connecting a UDP socket sends nothing)."""
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.connect((group, 9))
        return str(probe.getsockname()[0])
    except OSError:
        return "0.0.0.0"  # no route: sendto says so
    finally:
        probe.close()


def sending_socket(group: str, ttl: int | None = None) -> socket.socket:
    """A UDP socket that sends to `group` from the interface of its route, with `ttl` (None: the system's)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        if ttl is not None:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, ttl)
        source = socket.inet_aton(outgoing_address(group))
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, source)
    except BaseException:
        sock.close()
        raise
    return sock


def send_datagram(sock: socket.socket, payload: bytes, group: str, port: int) -> None:
    """Send `payload` to group:port; one RostoolError line when it cannot leave this machine."""
    try:
        sock.sendto(payload, (group, port))
    except OSError as err:
        problem = err.strerror or str(err)
        raise RostoolError(f"cannot send to {group}:{port}: {problem}; {ROUTE_HINT}") from None


def joined_socket(group: str, port: int) -> socket.socket:
    """A UDP socket on `port` (shared, as ros2's) that joined `group` on the interface of its route."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if hasattr(socket, "SO_REUSEPORT"):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
        try:
            sock.bind(("", port))
        except OSError as err:
            problem = err.strerror or str(err)
            raise RostoolError(f"cannot listen on UDP port {port}: {problem}; another program may hold it: "
                               "choose another --port on both ends") from None  # fmt: skip
        membership = struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton("0.0.0.0"))
        try:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
        except OSError as err:
            raise RostoolError(f"cannot join {group}: {err.strerror or err}; {ROUTE_HINT}") from None
    except BaseException:
        sock.close()
        raise
    return sock
