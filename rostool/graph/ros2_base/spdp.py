"""What other ROS 2 participants announce, read passively from the wire: every domain's multicast
discovery port (SPDP), which tells how many participants are there, their hosts and their middleware
(`rostool doctor`). Nothing here sends a packet; every message read is bounded by its datagram.

RTPS (DDS-RTPS 2.x, 9.6.1.1) puts domain D's multicast discovery at port 7400 + 250 D and participant p's
unicast discovery at 7410 + 250 D + 2 p; every RTPS message starts with "RTPS", the protocol version, the
vendor id and the sender's 12-byte GUID prefix; a participant's announcement (a DATA submessage) carries a
parameter list, where Fast DDS 3 puts its product version."""

from __future__ import annotations

import contextlib
import select
import socket
import struct
import time
from collections import defaultdict
from dataclasses import dataclass, field

from rostool.graph.ros2_base.env import DOMAIN_ID_MAX

PORT_BASE, DOMAIN_GAIN, UNICAST_OFFSET = 7400, 250, 10
SPDP_GROUP = "239.255.0.1"
LISTEN_SECONDS = 3.2  # Fast DDS announces a participant every 3 s (Cyclone every 30 s: a quiet one is missed)
VENDORS = {
    b"\x01\x01": "RTI Connext DDS (rmw_connextdds)",
    b"\x01\x0f": "eProsima Fast DDS (rmw_fastrtps_cpp)",
    b"\x01\x10": "Eclipse Cyclone DDS (rmw_cyclonedds_cpp, or rostool)",
    b"\x01\x12": "GurumNetworks GurumDDS (rmw_gurumdds_cpp)",
}


@dataclass
class Heard:
    """Participants announcing themselves on one domain."""

    participants: set[bytes] = field(default_factory=set)  # GUID prefixes
    hosts: set[str] = field(default_factory=set)
    vendors: set[str] = field(default_factory=set)
    releases: dict[str, set[str]] = field(default_factory=dict)  # middleware release -> hosts


PID_SENTINEL, PID_PRODUCT_VERSION = 0x0001, 0x8000  # the latter eProsima's: major, minor, patch, tweak
DATA_SUBMESSAGE = 0x15
# what a Fast DDS participant's announcement tells of its release (and so of its ROS 2 distro)
FAST_DDS = ("Fast DDS 2 (Jazzy or earlier)", "Fast DDS 3 (Kilted or later)")


def product_version(message: bytes) -> tuple[int, ...] | None:
    """The PID_PRODUCT_VERSION an SPDP message (DATA(p)) carries, or None: Fast DDS 3 (Kilted) announces
    it, Fast DDS 2 (Jazzy and earlier) does not. Bounded by the message: a malformed one gives None."""
    at = 20  # after the RTPS header
    while at + 4 <= len(message):
        kind, flags = message[at], message[at + 1]
        order = "<" if flags & 1 else ">"
        (length,) = struct.unpack_from(f"{order}H", message, at + 2)
        body = message[at + 4 : at + 4 + length]
        if kind == DATA_SUBMESSAGE and len(body) >= 24:
            (to_qos,) = struct.unpack_from(f"{order}H", body, 2)
            payload = body[4 + to_qos :]
            if flags & 0x2 or len(payload) < 4:  # inline QoS ahead of the data: not what SPDP sends
                return None
            pl_order = "<" if payload[:2] == b"\x00\x03" else ">"
            pos = 4
            while pos + 4 <= len(payload):
                pid, size = struct.unpack_from(f"{pl_order}HH", payload, pos)
                if pid == PID_SENTINEL:
                    return None
                if pid == PID_PRODUCT_VERSION and size >= 4:
                    return tuple(payload[pos + 4 : pos + 7])
                pos += 4 + size
            return None
        if length == 0:
            return None
        at += 4 + length
    return None


def release(message: bytes) -> str:
    """The middleware release an SPDP message shows, with the ROS 2 distros that ship it."""
    vendor = VENDORS.get(message[6:8], f"vendor {message[6:8].hex()}")
    if message[6:8] != b"\x01\x0f":
        return vendor
    version = product_version(message)
    return FAST_DDS[0] if version is None or version[0] < 3 else FAST_DDS[1]


def listen(seconds: float = LISTEN_SECONDS) -> dict[int, Heard]:
    """What every domain's multicast discovery port carries for `seconds` (our sockets share the ports with
    the participants of this machine, as they share them with each other)."""
    sockets: dict[socket.socket, int] = {}
    heard: dict[int, Heard] = defaultdict(Heard)
    try:
        for domain in range(DOMAIN_ID_MAX + 1):
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            with contextlib.suppress(AttributeError, OSError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
            try:
                sock.bind(("", PORT_BASE + DOMAIN_GAIN * domain))
                membership = struct.pack("4s4s", socket.inet_aton(SPDP_GROUP), socket.inet_aton("0.0.0.0"))
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
            except OSError:
                sock.close()
                continue
            sock.setblocking(False)
            sockets[sock] = domain
        deadline = time.monotonic() + seconds
        while sockets and (left := deadline - time.monotonic()) > 0:
            ready, _, _ = select.select(list(sockets), [], [], left)
            for sock in ready:
                with contextlib.suppress(OSError):
                    data, (host, _port) = sock.recvfrom(65536)
                    if len(data) >= 20 and data[:4] == b"RTPS":
                        entry = heard[sockets[sock]]
                        entry.participants.add(data[8:20])
                        entry.hosts.add(host)
                        entry.vendors.add(VENDORS.get(data[6:8], f"vendor {data[6:8].hex()}"))
                        entry.releases.setdefault(release(data), set()).add(host)
    finally:
        for sock in sockets:
            sock.close()
    return dict(heard)
