"""`rostool multicast send|receive` (ros2 multicast's verbs) between private machines (tests/netns.py): the
robot beside the laptop hears it, the far robot behind the router does not, and plain-Python sockets on the
other end agree byte for byte. Never in the host's own network namespace (CONTRIBUTING, "Network rule").
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys

import pytest

from tests.netns import LAN, PrivateNetwork
from tests.support import DEBIAN_PYTHON

MULTICAST = [sys.executable, "-m", "rostool", "multicast"]
WAITING = "Waiting for UDP multicast datagram..."
SENDING = "Sending one UDP multicast datagram...\n"
LAPTOP, ROBOT = f"{LAN}.10", f"{LAN}.20"
ROUTE_HINT = "is there a route for multicast (a default route or `ip route add 224.0.0.0/4 dev IFACE`)?"

# An independent receiver: bound to the group itself, joined on the robot's address, reading each datagram's
# TTL too (IP_RECVTTL, 12 on Linux; Python has no name for it). Prints "ready", then a JSON line per datagram.
PLAIN_RECEIVER = """
import json, socket, struct, sys
group, port, address, count = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
s.bind((group, port))
s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, socket.inet_aton(group) + socket.inet_aton(address))
s.setsockopt(socket.IPPROTO_IP, 12, 1)
s.settimeout(10)
print("ready", flush=True)
for _ in range(count):
    data, ancillary, _flags, sender = s.recvmsg(65535, socket.CMSG_SPACE(4))
    ttl = [struct.unpack("i", d)[0] for level, kind, d in ancillary if kind == socket.IP_TTL]
    print(json.dumps({"data": data.hex(), "from": sender[0], "port": sender[1], "ttl": ttl}), flush=True)
"""

# An independent sender: from a fixed port on the laptop's address, the payload given in hex.
PLAIN_SENDER = """
import socket, sys
group, port, address, source_port, payload = sys.argv[1:]
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind((address, int(source_port)))
s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton(address))
s.sendto(bytes.fromhex(payload), (group, int(port)))
"""

# Holds a UDP port without SO_REUSEADDR, as a program that owns it would.
PORT_HOLDER = """
import socket, sys, time
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("", int(sys.argv[1])))
print("ready", flush=True)
time.sleep(30)
"""


@pytest.fixture(scope="module")
def env() -> dict[str, str]:
    return {**os.environ, "PYTHONUNBUFFERED": "1"}


def _listening(receiver: subprocess.Popen[str], on_stderr: bool = False) -> None:
    """Wait until `receiver` joined the group (rostool says so once it has)."""
    stream = receiver.stderr if on_stderr else receiver.stdout
    assert stream is not None
    line = stream.readline()
    assert line.rstrip("\n") == WAITING, (line, receiver.communicate(timeout=10))


def _send_until_heard(
    network: PrivateNetwork, env: dict[str, str], receiver: subprocess.Popen[str], argv: list[str], says: str
) -> tuple[str, str]:
    """Send from the laptop until `receiver` ends (a switch may forward a group a moment after a join)."""
    for _ in range(5):
        sent = network.laptop.run(argv, env)
        assert (sent.returncode, sent.stdout, sent.stderr) == (0, says, "")
        try:
            return receiver.communicate(timeout=1)
        except subprocess.TimeoutExpired:
            continue
    receiver.kill()
    return receiver.communicate(timeout=10)


def test_robot_hears_the_laptop(network: PrivateNetwork, env: dict[str, str]) -> None:
    receiver = network.robot.popen([*MULTICAST, "receive", "-t", "10"], env)
    _listening(receiver)
    out, err = _send_until_heard(network, env, receiver, [*MULTICAST, "send"], SENDING)
    assert (receiver.returncode, err) == (0, "")
    assert re.fullmatch(rf"Received from {re.escape(LAPTOP)}:\d+: 'Hello World!'\n", out), out


def test_far_robot_hears_nothing(network: PrivateNetwork, env: dict[str, str]) -> None:
    receiver = network.far.popen([*MULTICAST, "receive", "--timeout", "1.5"], env)
    _listening(receiver)
    for argv in (["send"], ["send", "--ttl", "8"]):  # the router does not route multicast, whatever the TTL
        sent = network.laptop.run([*MULTICAST, *argv], env)
        assert (sent.returncode, sent.stdout, sent.stderr) == (0, SENDING, "")
    out, err = receiver.communicate(timeout=10)
    assert (receiver.returncode, out) == (1, "")
    assert err == (
        "rostool: no UDP multicast datagram on 225.0.0.1:49150 within 1.5 s: multicast does not reach this "
        "machine (is the sender on this subnet, and do the switch, Wi-Fi and firewall pass it?)\n"
    )


def test_plain_receiver_hears_rostool_byte_for_byte(network: PrivateNetwork, env: dict[str, str]) -> None:
    plain = [DEBIAN_PYTHON, "-c", PLAIN_RECEIVER, "225.0.0.1", "49150", ROBOT, "2"]
    receiver = network.robot.popen(plain, env)
    assert receiver.stdout is not None and receiver.stdout.readline() == "ready\n"
    for argv in (["send"], ["send", "--ttl", "3"]):
        sent = network.laptop.run([*MULTICAST, *argv], env)
        assert (sent.returncode, sent.stdout, sent.stderr) == (0, SENDING, "")
    out, err = receiver.communicate(timeout=15)
    assert (receiver.returncode, err) == (0, "")
    heard = [json.loads(line) for line in out.splitlines()]
    assert [(bytes.fromhex(d["data"]), d["from"], d["ttl"]) for d in heard] == [
        (b"Hello World!", LAPTOP, [1]),  # the system's multicast TTL, as ros2 leaves it
        (b"Hello World!", LAPTOP, [3]),
    ]


def test_rostool_hears_a_plain_sender(network: PrivateNetwork, env: dict[str, str]) -> None:
    group, port, payload = "239.255.0.7", "50000", "plain Python → rostool ✓".encode()
    argv = [*MULTICAST, "receive", "--group", group, "--port", port, "--json", "-t", "10"]
    receiver = network.robot.popen(argv, env)
    _listening(receiver, on_stderr=True)  # with --json, stdout has nothing but the JSON
    sender = [DEBIAN_PYTHON, "-c", PLAIN_SENDER, group, port, LAPTOP, "40001", payload.hex()]
    out, err = _send_until_heard(network, env, receiver, sender, "")
    assert (receiver.returncode, err) == (0, "")
    assert json.loads(out) == {"from": LAPTOP, "port": 40001, "data": "plain Python → rostool ✓"}
    assert out.count("\n") == 1


def test_ctrl_c_while_waiting_exits_quietly(network: PrivateNetwork, env: dict[str, str]) -> None:
    receiver = network.robot.popen([*MULTICAST, "receive"], env)
    _listening(receiver)
    receiver.send_signal(signal.SIGINT)
    out, err = receiver.communicate(timeout=10)
    assert (receiver.returncode, out, err) == (130, "", "")


def test_no_route_is_one_line(network: PrivateNetwork, env: dict[str, str]) -> None:
    # the lan switch's namespace has no address and no route at all
    sent = network.lan.run([*MULTICAST, "send"], env)
    assert (sent.returncode, sent.stdout) == (1, SENDING)
    assert sent.stderr == f"rostool: cannot send to 225.0.0.1:49150: Network is unreachable; {ROUTE_HINT}\n"
    heard = network.lan.run([*MULTICAST, "receive", "-t", "1"], env)
    assert (heard.returncode, heard.stdout) == (1, "")
    assert heard.stderr == f"rostool: cannot join 225.0.0.1: No such device; {ROUTE_HINT}\n"


def test_port_held_by_another_program_is_one_line(network: PrivateNetwork, env: dict[str, str]) -> None:
    holder = network.robot.popen([DEBIAN_PYTHON, "-c", PORT_HOLDER, "49151"], env)
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "ready\n"
        heard = network.robot.run([*MULTICAST, "receive", "--port", "49151", "-t", "1"], env)
    finally:
        holder.kill()
        holder.communicate(timeout=10)
    assert (heard.returncode, heard.stdout) == (1, "")
    assert heard.stderr == (
        "rostool: cannot listen on UDP port 49151: Address already in use; another program may hold it: "
        "choose another --port on both ends\n"
    )


def test_group_must_be_multicast(network: PrivateNetwork, env: dict[str, str]) -> None:
    sent = network.robot.run([*MULTICAST, "send", "--group", "198.18.1.20"], env)
    assert sent.returncode == 2 and sent.stdout == ""
    assert "Invalid value for '--group': '198.18.1.20' is not an IPv4 multicast group" in sent.stderr
