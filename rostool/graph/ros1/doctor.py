"""ROS 1's network checks for `rostool doctor` (roswtf's network rules): is the master reachable, can other
machines reach this one back, do the nodes' slave APIs answer, can this machine resolve the names they
advertise. Each check is a `Check`; nothing here changes the graph."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from urllib.parse import urlparse

from rostool.errors import RostoolError
from rostool.graph.base import NetworkCheck as Check
from rostool.graph.ros1 import env
from rostool.graph.ros1.master_client import MasterClient, call

NODE_TIMEOUT = 1.5  # seconds a node's slave API gets to answer getPid
NODES_AT_ONCE = 16


def checks() -> list[Check]:
    uri = env.master_uri()
    master_host = urlparse(uri).hostname or "localhost"
    found = [_advertised(master_host)]
    began = time.monotonic()
    master = MasterClient(uri, "/rostool_doctor")
    try:
        master.get_pid()
    except RostoolError as err:
        return [Check("master", False, f"{err}: is a master running there, is ROS_MASTER_URI right?"), *found]
    took = (time.monotonic() - began) * 1000
    found.insert(0, Check("master", True, f"{uri} answered in {took:.0f} ms"))
    found += _nodes(master)
    return found


def _advertised(master_host: str) -> Check:
    """The address this machine gives other nodes, and whether the master's machine can use it."""
    pinned = env.pinned_host()
    if pinned is not None:
        return _judge(pinned[1], f"from {pinned[0]}", master_host)
    if env.is_loopback(master_host):
        return Check("advertised address", True, "127.0.0.1 (the master is on this machine's loopback)")
    host = env.advertised_host()
    return _judge(host, "chosen by rostool: ROS_IP and ROS_HOSTNAME are unset", master_host)


def _judge(host: str, source: str, master_host: str) -> Check:
    address = host if _literal(host) else env.resolve(host)
    if address is None:
        return Check("advertised address", False, f"{host} ({source}) does not resolve on this machine: "
                     "other machines cannot call back; set ROS_IP to this machine's address")  # fmt: skip
    remote_master = not env.is_loopback(master_host)
    if env.is_loopback(address) and remote_master:
        route = env.route_source(master_host)
        fix = f"set ROS_IP={route}" if route else "set ROS_IP to this machine's address on the master's net"
        return Check("advertised address", False, f"{host} ({source}) resolves to {address}, loopback, while "
                     f"the master is at {master_host}: nodes there cannot call back; {fix}")  # fmt: skip
    shown = host if address == host else f"{host} = {address}"
    return Check("advertised address", True, f"{shown} ({source})")


def _literal(host: str) -> bool:
    return host.replace(".", "").isdigit() or ":" in host


def _nodes(master: MasterClient) -> list[Check]:
    """Every node's slave API asked getPid at once; host names this machine cannot resolve."""
    publishers, subscribers, services = master.system_state()
    names = sorted({node for _topic, nodes in (*publishers, *subscribers, *services) for node in nodes})
    uris: dict[str, str] = {}
    for name in names:
        try:
            uris[name] = master.lookup_node(name)
        except RostoolError:
            continue
    unresolved = sorted({host for host in (urlparse(u).hostname or "" for u in uris.values())
                         if host and not _literal(host) and env.resolve(host) is None})  # fmt: skip
    found = []
    if unresolved:
        whose = [f"{name} ({uri})" for name, uri in uris.items() if urlparse(uri).hostname in unresolved]
        found.append(Check("node host names", False, f"this machine cannot resolve {', '.join(unresolved)}, "
                           f"advertised by {', '.join(whose)}: add them to /etc/hosts, or set ROS_IP on "
                           "those machines"))  # fmt: skip
    else:
        found.append(Check("node host names", True, f"every host name of {len(uris)} nodes resolves"))

    def silent(item: tuple[str, str]) -> str | None:
        name, uri = item
        if urlparse(uri).hostname in unresolved:
            return None  # said above
        try:
            call(uri, "getPid", "/rostool_doctor", what=f"node {name}", timeout=NODE_TIMEOUT)
        except RostoolError:
            return f"{name} ({uri})"
        return None

    with ThreadPoolExecutor(NODES_AT_ONCE) as pool:
        dead = [entry for entry in pool.map(silent, uris.items()) if entry]
    if dead:
        found.append(Check("nodes answer", False, f"{len(dead)} of {len(uris)} nodes do not answer: "
                           f"{', '.join(dead)}; gone without unregistering (rosnode cleanup), or "
                           "unreachable from here"))  # fmt: skip
    else:
        found.append(Check("nodes answer", True, f"all {len(uris)} nodes answer"))
    return found
