"""`rostool daemon start|stop|status`: the user's private ROS 2 graph daemon (ros2 daemon's verbs)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import click

from rostool.commands._common import json_option, print_json, ros2_backend
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.graph import DaemonClient


def _client() -> DaemonClient:
    from rostool.graph import daemon_client

    return daemon_client(ros2_backend(click.get_current_context()))


@click.group()
def daemon() -> None:
    """The ROS 2 graph daemon: one per user and per graph (ROS_DOMAIN_ID, backend, RMW, discovery and
    DDS profile variables), reached through a private Unix socket. The first ROS 2 listing starts it;
    --no-daemon or ROSTOOL_NO_DAEMON=1 on a verb asks the graph directly. It exits after
    ROSTOOL_DAEMON_IDLE seconds without a query (default 2 h), on `daemon stop` and on SIGTERM.

    \b
    Examples:
      rostool daemon status --json
      rostool --ros2 daemon stop
    """


@daemon.command()
@click.option("--idle", type=float, metavar="S", help="Exit after S seconds without a query.")
@click.option("--debug", is_flag=True, help="Print where the daemon logs (ros2cli's flag).")
def start(idle: float | None, debug: bool) -> None:
    """Start the daemon of this graph, if it is not running, and wait until it answers.

    \b
    Examples:
      rostool daemon start
      rostool daemon start --idle 600   # exit after 10 minutes without a query
    """
    client = _client()
    if client.status() is not None:
        click.echo("The daemon is already running")
        return
    started = client.start_detached(idle) if client.lock_holder() is None else None
    if client.wait_ready(started) is None:
        raise RostoolError(f"the graph daemon did not start; its log says why: {client.place.log}")
    click.echo("The daemon has been started")
    if debug:
        click.echo(f"log: {client.place.log}")


@daemon.command()
@click.option("--all", "every", is_flag=True, help="Stop every daemon of yours (all domains and keys).")
def stop(every: bool) -> None:
    """Stop the daemon of this graph (with --all, every daemon of this user).

    \b
    Examples:
      rostool daemon stop
      rostool daemon stop --all
    """
    from rostool.graph import every_daemon_client

    clients = every_daemon_client() if every else [_client()]
    stopped = [client for client in clients if client.stop()]
    click.echo("The daemon has been stopped" if stopped else "The daemon is not running")


@daemon.command()
@json_option
def status(as_json: bool) -> None:
    """Whether the daemon of this graph runs (or is starting): its pid, socket, backend, domain, uptime,
    graph size and the queries it has answered.

    \b
    Examples:
      rostool daemon status
      ROS_DOMAIN_ID=7 rostool daemon status --json
    """
    client = _client()
    found: dict[str, Any] = client.status() or {"running": False, "socket": str(client.place.socket)}
    if not found["running"]:
        holder = client.lock_holder()  # held while a daemon settles its graph, before it serves
        found["starting"] = holder is not None
        if holder is not None:
            found["pid"] = holder
    if as_json:
        print_json(found)
        return
    if not found["running"]:
        starting = f"starting (pid {found['pid']})" if found["starting"] else "not running"
        click.echo(f"The daemon is {starting}")
        return
    click.echo("The daemon is running")
    size = found["graph"]
    click.echo(f"  pid: {found['pid']}\n  socket: {found['socket']}\n  backend: {found['backend']}")
    click.echo(f"  domain: {found['domain']}\n  uptime: {found['uptime']:.1f} s\n  log: {found['log']}")
    click.echo(f"  graph: {size['nodes']} nodes, {size['topics']} topics, {size['services']} services, "
               f"{size['actions']} actions")  # fmt: skip
    relays = found.get("relays") or []
    click.echo(f"  relays: {len(relays)}" + (f" ({', '.join(relays)})" if relays else ""))
    click.echo(f"  queries answered: {found.get('queries', 0)}")
    if "idle_exit" in found:  # a daemon of an older build does not say
        by = "started by a verb" if found.get("auto_started") else "started by `daemon start`"
        click.echo(f"  exits after: {found['idle_exit']:g} s without a query or relay ({by}; "
                   f"idle for {found['idle']:.1f} s)")  # fmt: skip
