"""`rostool multicast send|receive`: does UDP multicast pass between two machines? (ros2 multicast's verbs)

The same group, port, datagram and lines as ros2multicast, so rostool and ros2 can be at either end. The
sockets are `rostool.graph.multicast`'s (shared with `doctor hello`): only the standard library, nothing of
ROS.
"""

from __future__ import annotations

import contextlib
import ipaddress

import click

from rostool.commands._common import json_option, print_json
from rostool.errors import RostoolError
from rostool.graph.multicast import GROUP, PORT, joined_socket, send_datagram, sending_socket

GREETING = b"Hello World!"


def _multicast_group(_ctx: click.Context, _param: click.Parameter, value: str) -> str:
    with contextlib.suppress(ValueError):
        if ipaddress.IPv4Address(value).is_multicast:
            return value
    raise click.BadParameter(f"{value!r} is not an IPv4 multicast group (224.0.0.0 to 239.255.255.255)")


group_option = click.option(
    "--group", default=GROUP, show_default=True, metavar="ADDRESS", callback=_multicast_group,
    help="The multicast group address.",
)  # fmt: skip
port_option = click.option(
    "--port", type=click.IntRange(1, 65535), default=PORT, show_default=True, metavar="PORT",
    help="The UDP port.",
)  # fmt: skip


@click.group()
def multicast() -> None:
    """Check that UDP multicast passes between two machines, like `ros2 multicast` (ROS 2's default
    discovery needs it): `receive` on one machine waits for one datagram, `send` on another sends it.

    \b
    Examples:
      rostool multicast receive     # on the robot: waits for the datagram
      rostool multicast send        # then on the laptop
    """


@multicast.command(
    epilog="""\b
Examples:
  rostool multicast send                    # to 225.0.0.1:49150, heard by `multicast receive`
  Sending one UDP multicast datagram...
  rostool multicast send --ttl 4            # may cross up to 3 multicast routers
  rostool multicast send --group 239.255.0.7 --port 50000
"""
)
@group_option
@port_option
@click.option("--ttl", type=click.IntRange(1, 255), metavar="N", help="The multicast TTL (default: 1).")
def send(group: str, port: int, ttl: int | None) -> None:
    """Send one UDP multicast datagram, 'Hello World!'."""
    click.echo("Sending one UDP multicast datagram...")
    with sending_socket(group, ttl) as sock:
        send_datagram(sock, GREETING, group, port)


@multicast.command(
    epilog="""\b
Examples:
  rostool multicast receive                 # on the robot, then `multicast send` on the laptop
  Waiting for UDP multicast datagram...
  Received from 198.18.1.10:45678: 'Hello World!'
  rostool multicast receive -t 5            # give up after 5 s (exit 1)
  rostool multicast receive --json          # {"from": "198.18.1.10", "port": 45678, "data": "Hello World!"}
"""
)
@group_option
@port_option
@click.option("-t", "--timeout", type=click.FloatRange(0, min_open=True), metavar="S",
              help="Give up after S seconds without a datagram: one line on stderr, exit 1 "
              "(default: wait until Ctrl+C).")  # fmt: skip
@json_option
def receive(group: str, port: int, timeout: float | None, as_json: bool) -> None:
    """Wait for one UDP multicast datagram and print who sent it and what it says."""
    with joined_socket(group, port) as sock:
        click.echo("Waiting for UDP multicast datagram...", err=as_json)
        sock.settimeout(timeout)
        try:
            data, (host, sender_port) = sock.recvfrom(65535)
        except TimeoutError:
            raise RostoolError(
                f"no UDP multicast datagram on {group}:{port} within {timeout:g} s: multicast does not reach "
                "this machine (is the sender on this subnet, and do the switch, Wi-Fi and firewall pass it?)"
            ) from None
    text = data.decode("utf-8", errors="backslashreplace")
    if as_json:
        print_json({"from": host, "port": sender_port, "data": text})
    else:
        click.echo(f"Received from {host}:{sender_port}: '{text}'")
