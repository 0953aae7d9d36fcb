"""`rostool doctor`: which ROS version, ROS 2 backend, RMW, distro, domain and discovery range a command
would use, and why (in the spirit of `ros2 doctor --report`)."""

from __future__ import annotations

from typing import Any

import click

from rostool.commands._common import json_option, print_json, ros2_backend, ros_version


@click.command("doctor")
@json_option
@click.pass_context
def doctor(ctx: click.Context, as_json: bool) -> None:
    """Show what the graph verbs would use and why: ROS version, ROS 2 backend (rclpy or rostool's own
    DDS), RMW, distro, domain and discovery range. Opens no graph.

    \b
    Examples:
      rostool doctor
      rostool --ros2-backend rclpy doctor --json
    """
    from rostool.errors import RostoolError
    from rostool.graph import ros2_report, select_ros_version

    explicit = ros_version(ctx)
    version = select_ros_version(explicit)
    report: dict[str, Any] = {"ros_version": version, "ros_version_from": _version_source(explicit, version)}
    try:
        report["ros2"] = ros2_report(ros2_backend(ctx))
    except RostoolError as err:  # the backend asked for cannot serve: say so, and why, as a graph verb would
        report["ros2"] = {"backend": None, "error": str(err)}
    if as_json:
        print_json(report)
    else:
        _print(report)
    if report["ros2"]["backend"] is None:
        ctx.exit(1)


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
