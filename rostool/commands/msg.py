"""`rostool msg`: show, list, md5 (rosmsg's forms) for the ROS 1 message types rostool knows."""

from __future__ import annotations

import click

from rostool.commands._common import json_option, print_json
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


def _matches(type_name: str) -> list[str]:
    """Store names for `pkg/Type`, or for a bare `Type` in every package that has one (as rosmsg does)."""
    from rostool.interfaces.names import to_store_name
    from rostool.interfaces.ros1 import builtin_store

    store = builtin_store()
    if "/" in type_name:
        name = to_store_name(type_name)
        return [name] if name in store.fielddefs else []
    return sorted(n for n in store.fielddefs if n.endswith(f"/msg/{type_name}"))


@msg.command("show")
@click.argument("type_name", metavar="TYPE")
@click.pass_context
def show(ctx: click.Context, type_name: str) -> None:
    """Print the fields of a message type (nested types expanded).

    \b
    Example:
      rostool msg show geometry_msgs/Twist
    """
    from rostool.interfaces.describe import describe
    from rostool.interfaces.names import to_ros1_name
    from rostool.interfaces.ros1 import builtin_store

    found = _matches(type_name)
    if not found:
        raise RostoolError(f"unknown message type {type_name!r} (see `rostool msg list`)")
    store = builtin_store()
    if len(found) == 1 and "/" in type_name:
        click.echo("\n".join(describe(store, found[0])) + "\n")
        return
    for name in found:
        click.echo(f"[{to_ros1_name(name)}]:")
        click.echo("\n".join(describe(store, name)) + "\n")


@msg.command("list")
@json_option
def list_types(as_json: bool) -> None:
    """List the message types rostool knows.

    \b
    Example:
      rostool msg list | grep geometry_msgs
    """
    from rostool.interfaces.names import to_ros1_name
    from rostool.interfaces.ros1 import builtin_store

    names = sorted(to_ros1_name(n) for n in builtin_store().fielddefs if "/msg/" in n)
    if as_json:
        print_json(names)
    else:
        click.echo("\n".join(names))


@msg.command("md5")
@click.argument("type_name", metavar="TYPE")
def md5(type_name: str) -> None:
    """Print the md5sum of a message type (what ROS 1 peers compare).

    \b
    Example:
      rostool msg md5 std_msgs/String      # 992ce8a1687cec8c8bd883ec73ca41d1
    """
    from rostool.interfaces.ros1 import TypeRegistry

    click.echo(TypeRegistry().builtin(type_name).md5sum)
