"""`rostool doctor`: which ROS version, ROS 2 backend, RMW, distro, domain and discovery range a command
would use, and why, then the network checks of that ROS version (roswtf's and `ros2 doctor`'s job): one
line per failed check and exit 1, or `--report` for every check and fact. A group, as ros2 doctor's: its
verbs (`hello`: doctor_hello.py) are imported only when run."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import ExtensibleGroup, json_option, print_json, ros2_backend, ros_version
from rostool.graph.base import NetworkCheck

EPILOG = """\b
Examples:
  rostool doctor                            # one line per failed check; exit 1 if any
  rostool doctor --report                   # every check and fact
  rostool --ros2-backend rclpy doctor --json
  rostool doctor hello                      # on the laptop and on the robot: do they hear each other?
"""


@click.group(
    "doctor", cls=ExtensibleGroup, invoke_without_command=True, epilog=EPILOG,
    extra={"hello": "rostool.commands.doctor_hello:hello"},
)  # fmt: skip
@click.option("--report", "full", is_flag=True, help="Every check and network fact, not only what failed.")
@click.option("--listen", type=click.FloatRange(0, 30), default=None,
              help="ROS 2: seconds to listen for other machines' participants (3.2); 0: look at this "
              "machine only (no multicast test, nothing sent).")  # fmt: skip
@json_option
@click.pass_context
def doctor(ctx: click.Context, full: bool, listen: float | None, as_json: bool) -> None:
    """Show what the graph verbs would use and why (ROS version, ROS 2 backend, RMW, distro, domain and
    discovery range), then check the network. ROS 1: the master answers, the address this machine
    advertises reaches back, every node's slave API answers, their host names resolve. ROS 2: the static
    peers resolve; which domains this machine's participants use, and (SUBNET) which domains other machines
    announce participants on, listened to passively, and whether multicast works on each interface; a
    domain with nothing on it names the one in use. Each failed check is one line, and the exit status is
    1. Opens no graph.

    `rostool doctor hello` (ros2 doctor hello) checks that machines hear each other on a topic and by
    UDP multicast.
    """
    if ctx.invoked_subcommand is not None:
        given = [flag for flag, used in (("--report", full), ("--listen", listen is not None),
                                         ("--json", as_json)) if used]  # fmt: skip
        if given:
            raise click.UsageError(f"{', '.join(given)}: options of `rostool doctor` alone, not of its verbs")
        return
    from rostool.errors import RostoolError
    from rostool.graph import network_checks, ros2_report, select_ros_version

    explicit = ros_version(ctx)
    version = select_ros_version(explicit)
    report: dict[str, Any] = {"ros_version": version, "ros_version_from": _version_source(explicit, version)}
    try:
        report["ros2"] = ros2_report(ros2_backend(ctx))
    except RostoolError as err:  # the backend asked for cannot serve: say so, and why, as a graph verb would
        report["ros2"] = {"backend": None, "error": str(err)}
    failed = report["ros2"]["backend"] is None
    try:
        facts, checks = network_checks(version, listen)
    except RostoolError as err:  # e.g. a ROS_DOMAIN_ID or ROS_MASTER_URI that is not valid
        facts, checks = {}, [NetworkCheck("environment", False, str(err))]
    report["network"] = facts
    report["checks"] = [{"name": c.name, "ok": c.ok, "detail": c.detail} for c in checks]
    if as_json:
        print_json(report)
    else:
        _print(report)
        _print_checks(checks, facts, full)
    if failed or not all(check.ok for check in checks):
        ctx.exit(1)


def _print_checks(checks: list[NetworkCheck], facts: dict[str, Any], full: bool) -> None:
    if full:  # the facts the table above has not shown
        for name, value in facts.items():
            if name not in ("domain", "range"):
                click.echo(f"{name.replace('_', ' ')} : {value}")
    for check in checks:
        if full or not check.ok:
            click.echo(f"{'ok' if check.ok else 'FAILED'} {check.name}: {check.detail}")
    bad = sum(not check.ok for check in checks)
    count = len(checks)
    click.echo(f"{bad} of {count} network checks failed" if bad else f"All {count} network checks passed")


def _print(report: dict[str, Any]) -> None:
    ros2 = report["ros2"]
    rows = [("ROS version", f"{report['ros_version']} ({report['ros_version_from']})")]
    if ros2["backend"] is None:
        rows.append(("ROS 2 backend", f"none: {ros2['error']}"))
        click.echo("\n".join(f"{name} : {value}" for name, value in rows))
        return
    rows.append(("ROS 2 backend", f"{ros2['backend']} ({ros2['reason']})"))
    if "rclpy" in ros2:
        rows.append(("rclpy", f"{ros2['rclpy']['version'] or '?'} at {ros2['rclpy']['path']}"))
    rows += [
        ("RMW", f"{ros2['rmw']} ({ros2['rmw_from']})"),
        ("distro", f"{ros2['distro'] or 'unknown'} ({ros2['distro_from']})"),
        ("domain", f"{ros2['domain_id']} ({ros2['domain_id_from']})"),
        ("discovery range", f"{ros2['discovery_range']} ({ros2['discovery_range_from']})"),
    ]
    rows += [(name, value) for name, value in ros2["middleware_settings"].items()]
    width = max(len(name) for name, _ in rows)
    click.echo("\n".join(f"{name.ljust(width)} : {value}" for name, value in rows))


def _version_source(explicit: int | None, version: int) -> str:
    import os

    if explicit is not None:
        return f"--ros{explicit}"
    if os.environ.get("ROS_VERSION", "").strip() in ("1", "2"):
        return "ROS_VERSION"
    if os.environ.get("ROS_MASTER_URI"):
        return "ROS_MASTER_URI is set"
    if version == 1:
        return "a master answers on localhost:11311"
    return "no ROS_VERSION, no ROS_MASTER_URI, no master on localhost:11311"
