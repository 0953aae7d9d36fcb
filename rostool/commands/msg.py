"""`rostool msg`: show, list, md5 (rosmsg's forms) for the ROS 1 message types rostool knows."""

from __future__ import annotations

import click

from rostool.commands._common import json_option, print_json
from rostool.commands.srv import interfaces_option
from rostool.errors import RostoolError


@click.group()
def msg() -> None:
    """Show message types (like rosmsg).

    \b
    Examples:
      rostool msg show geometry_msgs/PoseStamped
      rostool msg show String
      rostool msg list
    """


def _matches(type_name: str, paths: tuple[str, ...] = ()) -> list[str]:
    """`pkg/Type` if known, or every package's `Type` for a bare name (as rosmsg does); custom types too."""
    from rostool.interfaces.names import to_ros1_name, to_store_name
    from rostool.interfaces.sources import interfaces

    catalog = interfaces(paths)
    if "/" in type_name:
        name = to_ros1_name(to_store_name(type_name))
        return [name] if catalog.has_message(name) else []
    return [n for n in catalog.message_names() if n.endswith(f"/{type_name}")]


@msg.command("show")
@click.argument("type_name", metavar="TYPE")
@interfaces_option
@click.pass_context
def show(ctx: click.Context, type_name: str, interface_paths: tuple[str, ...]) -> None:
    """Print the fields of a message type (nested types expanded), built in or from .msg/.action files.

    \b
    Examples:
      rostool msg show geometry_msgs/Twist
      rostool msg show robot_navigation_pkg/MoveToPointActionGoal --interfaces ~/catkin_ws
    """
    from rostool.interfaces.sources import interfaces

    found = _matches(type_name, interface_paths)
    if not found:
        raise RostoolError(f"unknown message type {type_name!r} (see `rostool msg list`)")
    catalog = interfaces(interface_paths)
    if len(found) == 1 and "/" in type_name:
        click.echo("\n".join(catalog.show_lines(found[0])) + "\n")
        return
    for name in found:
        click.echo(f"[{name}]:")
        click.echo("\n".join(catalog.show_lines(name)) + "\n")


@msg.command("list")
@interfaces_option
@json_option
def list_types(interface_paths: tuple[str, ...], as_json: bool) -> None:
    """List the message types rostool knows (built in, and from .msg/.action files in the sources).

    \b
    Example:
      rostool msg list | grep geometry_msgs
    """
    from rostool.interfaces.sources import interfaces

    names = interfaces(interface_paths).message_names()
    if as_json:
        print_json(names)
    else:
        click.echo("\n".join(names))


@msg.command("md5")
@click.argument("type_name", metavar="TYPE")
@interfaces_option
def md5(type_name: str, interface_paths: tuple[str, ...]) -> None:
    """Print the md5sum of a message type (what ROS 1 peers compare).

    \b
    Example:
      rostool msg md5 std_msgs/String      # 992ce8a1687cec8c8bd883ec73ca41d1
    """
    from rostool.interfaces.sources import interfaces

    click.echo(interfaces(interface_paths).md5(type_name))
