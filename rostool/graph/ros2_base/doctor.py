"""ROS 2's network checks for `rostool doctor`, from the wire up, whatever the backend: the domain, range,
static peers and interfaces discovery uses; whether each interface carries multicast; the participants of
this machine on each domain (the UDP ports they hold, read from /proc: no packet sent); and, where discovery
may use multicast, what other machines announce on every domain (`spdp.py`, heard passively)."""

from __future__ import annotations

import contextlib
import os
import socket
import struct
from collections import defaultdict
from collections.abc import Mapping
from pathlib import Path

from rostool.graph.base import NetworkCheck as Check
from rostool.graph.ros2_base.env import DOMAIN_ID_MAX, discovery_range, domain_id, static_peers
from rostool.graph.ros2_base.spdp import (
    DOMAIN_GAIN,
    FAST_DDS,
    LISTEN_SECONDS,
    PORT_BASE,
    UNICAST_OFFSET,
    Heard,
    listen,
)


def local_domains(proc: Path = Path("/proc/net")) -> dict[int, int]:
    """Domain -> how many participants of this machine (this network namespace) use it, from the UDP ports
    in /proc/net/udp and udp6: a participant holds a pair of ports, discovery and data (7410 + 250 D + 2 p
    and the next; with SUBNET also the domain's multicast pair 7400 + 250 D and the next). Only pairs count:
    a lone ephemeral port (Cyclone's without a participant index, any socket's) lands among them at random.
    This process's own sockets are left out."""
    own = _own_socket_inodes()
    ports: set[int] = set()
    for name in ("udp", "udp6"):
        with contextlib.suppress(OSError), open(proc / name, encoding="ascii") as table:
            next(table, None)
            for line in table:
                fields = line.split()
                if len(fields) > 9 and fields[9] not in own:
                    ports.add(int(fields[1].rsplit(":", 1)[1], 16))
    held: dict[int, set[int]] = defaultdict(set)
    for port in ports:
        domain, offset = divmod(port - PORT_BASE, DOMAIN_GAIN)
        if port < PORT_BASE or domain > DOMAIN_ID_MAX or offset % 2 or port + 1 not in ports:
            continue
        if offset >= UNICAST_OFFSET:
            held[domain].add((offset - UNICAST_OFFSET) // 2)
        elif offset == 0:
            held.setdefault(domain, set())
    return {domain: max(1, len(indexes)) for domain, indexes in sorted(held.items())}


def _own_socket_inodes() -> set[str]:
    inodes = set()
    with contextlib.suppress(OSError):
        for fd in os.listdir("/proc/self/fd"):
            with contextlib.suppress(OSError):
                target = os.readlink(f"/proc/self/fd/{fd}")
                if target.startswith("socket:["):
                    inodes.add(target[8:-1])
    return inodes


def empty_listing_hint(domain: int, scope: str) -> str:
    """Why a listing found nobody, where this machine can see it without sending anything: its participants
    are on another domain, or (SUBNET) no interface can carry multicast. "" when nothing is visible."""
    elsewhere = {d: n for d, n in local_domains().items() if d != domain}
    if elsewhere:
        shown = ", ".join(f"{n} on domain {d}" for d, n in elsewhere.items())
        best = max(elsewhere, key=lambda d: elsewhere[d])
        return f"; this machine's participants are elsewhere ({shown}): set ROS_DOMAIN_ID={best}?"
    if scope in ("SUBNET", "SYSTEM_DEFAULT"):
        states = {name: _carrier(name) for name, address in interfaces() if not address.startswith("127.")}
        if not any(state is None for state in states.values()):
            shown = ", ".join(f"{name}: {state}" for name, state in states.items()) or "only loopback"
            return f"; no interface can carry multicast ({shown}): is the network up?"
    return ""


def _carrier(name: str) -> str | None:
    """None when the interface is up with a carrier and can multicast, else what it lacks."""
    try:
        flags = _flags(name)
    except OSError as err:
        return err.strerror or str(err)
    for flag, missing in ((IFF_UP, "down"), (IFF_RUNNING, "no carrier (cable, Wi-Fi?)"),
                          (IFF_MULTICAST, "no MULTICAST flag")):  # fmt: skip
        if not flags & flag:
            return missing
    return None


def interfaces() -> list[tuple[str, str]]:
    """(name, IPv4 address) of this machine's interfaces that have one."""
    import fcntl

    found = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        for _index, name in socket.if_nameindex():
            request = struct.pack("256s", name.encode()[:15])
            try:
                reply = fcntl.ioctl(probe.fileno(), 0x8915, request)  # SIOCGIFADDR
            except OSError:
                continue
            found.append((name, socket.inet_ntoa(reply[20:24])))
    return found


IFF_UP, IFF_RUNNING, IFF_MULTICAST = 0x1, 0x40, 0x1000
LOOP_GROUP = "239.255.0.250"  # a group of the organisation-local scope no ROS vendor uses


def _flags(name: str) -> int:
    import fcntl

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        reply = fcntl.ioctl(probe.fileno(), 0x8913, struct.pack("256s", name.encode()[:15]))  # SIOCGIFFLAGS
    return int(struct.unpack_from("H", reply, 16)[0])


def multicast_on(name: str, address: str) -> str | None:
    """Whether multicast works on one interface: it is up, has a carrier and the MULTICAST flag, and a
    datagram sent with TTL 0 (it never leaves this machine) to a group joined there comes back. None when it
    does, else why not."""
    lacking = _carrier(name)
    if lacking is not None:
        return lacking
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP) as sock:
            sock.bind(("", 0))
            port = sock.getsockname()[1]
            local = socket.inet_aton(address)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, socket.inet_aton(LOOP_GROUP) + local)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, local)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
            sock.settimeout(0.3)
            token = os.urandom(8)
            sock.sendto(token, (LOOP_GROUP, port))
            while True:
                if sock.recv(64) == token:
                    return None
    except OSError as err:
        return f"a datagram to {LOOP_GROUP} did not come back ({err.strerror or err})"


def _multicast_check(used: list[tuple[str, str]]) -> Check:
    verdicts = {f"{name} {address}": multicast_on(name, address)
                for name, address in used if not address.startswith("127.")}  # fmt: skip
    shown = "; ".join(f"{where}: {'works' if why is None else why}" for where, why in verdicts.items())
    if any(why is None for why in verdicts.values()):
        return Check("multicast", True, shown)
    return Check("multicast", False, f"no interface carries multicast ({shown or 'only loopback'}): SUBNET "
                 "discovery needs one; name the other machines in ROS_STATIC_PEERS")  # fmt: skip


def checks(env: Mapping[str, str], seconds: float = LISTEN_SECONDS) -> tuple[dict[str, object], list[Check]]:
    """The facts of discovery and the checks, as `doctor` shows them."""
    domain, scope, peers = domain_id(env), discovery_range(env), static_peers(env)
    used = interfaces()
    if scope == "LOCALHOST" and not peers:
        used = [(name, address) for name, address in used if address.startswith("127.")]
    facts: dict[str, object] = {
        "domain": domain, "range": scope, "static_peers": peers,
        "interfaces": [f"{name} {address}" for name, address in used],
    }  # fmt: skip
    found: list[Check] = []
    unresolved = [peer for peer in peers if _resolves(peer) is None]
    if peers:
        found.append(Check("static peers", not unresolved, f"{', '.join(unresolved)} do not resolve here"
                           if unresolved else f"{len(peers)} resolve: {', '.join(peers)}"))  # fmt: skip
    local = local_domains()
    # seconds == 0: read this machine only (join no group, send nothing)
    multicast = scope in ("SUBNET", "SYSTEM_DEFAULT") and seconds > 0
    if multicast:
        found.append(_multicast_check(used))
    heard = listen(seconds) if multicast else {}
    facts["this_machine"] = {str(d): n for d, n in local.items()}
    facts["heard"] = {str(d): _heard_facts(h) for d, h in sorted(heard.items())}
    listened = seconds if multicast else None
    found.append(_domain_check(domain, local, heard, listened))
    vendors = {v for h in heard.values() for v in h.vendors}
    if len(vendors) > 1:
        named = ", ".join(sorted(vendors))
        found.append(Check("middleware", True, f"several DDS vendors announce here: {named} (topics "
                           "interoperate; services between some do not)"))  # fmt: skip
    fast = {name: hosts for h in heard.values() for name, hosts in h.releases.items() if name in FAST_DDS}
    if len(fast) > 1:
        shown = "; ".join(f"{name} on {', '.join(sorted(hosts))}" for name, hosts in sorted(fast.items()))
        found.append(Check("distros", False, f"several ROS 2 distros announce here ({shown}): ROS 2 "
                           "supports one distro per graph; messages and services may not match"))  # fmt: skip
    return facts, found


def _heard_facts(heard: Heard) -> dict[str, object]:
    releases = {name: sorted(hosts) for name, hosts in sorted(heard.releases.items())}
    return {"participants": len(heard.participants), "hosts": sorted(heard.hosts),
            "vendors": sorted(heard.vendors), "releases": releases}  # fmt: skip


def _domain_check(
    domain: int, local: dict[int, int], heard: dict[int, Heard], listened: float | None
) -> Check:
    here = local.get(domain, 0) + len(heard.get(domain, Heard()).participants)
    if here:
        hosts = sorted(heard.get(domain, Heard()).hosts)
        whom = f" (heard from {', '.join(hosts)})" if hosts else " (on this machine)"
        return Check("domain", True, f"participants on domain {domain}{whom}")
    others: dict[int, tuple[int, set[str]]] = {}
    for d, count in local.items():
        others[d] = (count, {"this machine"})
    for d, entry in heard.items():
        count, hosts = others.get(d, (0, set()))
        others[d] = (max(count, len(entry.participants)), hosts | entry.hosts)
    others.pop(domain, None)
    if not others:  # nothing running is not a fault of the network: said, not failed
        how = "on this machine" + (f" or by multicast within {listened:g} s" if listened else "")
        return Check("domain", True, f"no ROS 2 participant on any domain ({how})")
    best = max(others, key=lambda d: others[d][0])
    shown = "; ".join(f"{n} participants on domain {d} (hosts {', '.join(sorted(h))})"
                      for d, (n, h) in sorted(others.items()))  # fmt: skip
    return Check("domain", False, f"nothing on domain {domain}; {shown}: set ROS_DOMAIN_ID={best}")


def _resolves(host: str) -> str | None:
    try:
        return socket.gethostbyname(host)
    except (OSError, UnicodeError):
        return None
