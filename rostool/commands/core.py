"""`rostool core`: run the embedded ROS 1 master and parameter server until Ctrl+C."""

from __future__ import annotations

import signal
from types import FrameType

import click

from rostool.graph import MASTER_HOST, MASTER_PORT, embedded_master


@click.command(
    "core",
    epilog="""\b
Examples:
  rostool core                      # master on http://127.0.0.1:11311/
  rostool core --port 11312         # a second master next to a running one
  ROS_MASTER_URI=http://127.0.0.1:11312 rostool topic list
""",
)
@click.option(
    "--port",
    type=click.IntRange(0, 65535),
    default=MASTER_PORT,
    show_default=True,
    help="TCP port to serve (0: any free port).",
)
@click.option(
    "--host",
    default=MASTER_HOST,
    show_default=True,
    help="Address to listen on. The default serves this machine only; 0.0.0.0 serves every network "
    "interface and advertises ROS_HOSTNAME, ROS_IP or the host name.",
)
def core(port: int, host: str) -> None:
    """Run a ROS 1 master and parameter server, like roscore (without rosout).

    Sets /rosdistro ($ROS_DISTRO, else noetic), /rosversion and /run_id as roscore does, and serves
    until Ctrl+C or SIGTERM. Nodes, rostool and the ROS 1 tools find it through ROS_MASTER_URI.
    """
    master = embedded_master(host, port)
    received: list[int] = []

    def on_signal(signum: int, _frame: FrameType | None) -> None:
        # Only record it: taking a lock here could deadlock with the main thread's wait().
        received.append(signum)

    # Ctrl+C and SIGTERM are the normal way to stop a master: exit 0, not the 130 of an interrupt.
    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        uri = master.start()
        click.echo(f"started rostool core at {uri} (ROS_MASTER_URI)", err=True)
        while not received and not master.wait(0.2):
            pass
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        master.stop()
    if master.stop_reason.startswith("shutdown request"):
        click.echo(f"rostool core stopped: {master.stop_reason}", err=True)
