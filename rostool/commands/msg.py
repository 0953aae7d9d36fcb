"""`rostool msg`: show, list, md5 (rosmsg's forms) for the ROS 1 message types rostool knows; on ROS 2
(--ros2, ROS_VERSION=2 or a `pkg/msg/T` name) show and list in `ros2 interface`'s forms, md5 as RIHS01."""

from __future__ import annotations

import click

from rostool.commands._common import interface_style, interfaces_option, json_option, print_json
from rostool.errors import RostoolError


@click.group()
def msg() -> None:
    """Show message types (like rosmsg).

    \b
    Examples:
      rostool msg show geometry_msgs/PoseStamped
      rostool msg show String
      rostool msg list
      rostool --ros2 msg show geometry_msgs/msg/PoseStamped
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

    On ROS 2 (--ros2, ROS_VERSION=2 or a pkg/msg/Type name) it prints what `ros2 interface show
    --no-comments` does, for .srv and .action types too (pkg/srv/Type, pkg/action/Type).

    \b
    Examples:
      rostool msg show geometry_msgs/Twist
      rostool msg show robot_navigation_pkg/MoveToPointActionGoal --interfaces ~/catkin_ws
      rostool --ros2 msg show geometry_msgs/msg/PoseStamped
      rostool msg show example_interfaces/srv/AddTwoInts
    """
    from rostool.interfaces.sources import interfaces

    if interface_style(ctx, type_name) == "ros2":
        from rostool.interfaces.describe_ros2 import show_text

        click.echo(show_text(type_name, "msg", interface_paths), nl=False)
        return

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
@click.option("-m", "--only-msgs", is_flag=True, help="ROS 2: only the message types.")
@click.option("-s", "--only-srvs", is_flag=True, help="ROS 2: only the service types.")
@click.option("-a", "--only-actions", is_flag=True, help="ROS 2: only the action types.")
@interfaces_option
@json_option
@click.pass_context
def list_types(
    ctx: click.Context,
    only_msgs: bool,
    only_srvs: bool,
    only_actions: bool,
    interface_paths: tuple[str, ...],
    as_json: bool,
) -> None:
    """List the message types rostool knows (built in, and from .msg/.action files in the sources).

    On ROS 2 it prints what `ros2 interface list` does: Messages:, Services: and Actions: sections, or only
    those of -m, -s, -a.

    \b
    Examples:
      rostool msg list | grep geometry_msgs
      rostool --ros2 msg list -m
    """
    from rostool.interfaces.sources import interfaces

    only = [k for k, flag in (("msg", only_msgs), ("srv", only_srvs), ("action", only_actions)) if flag]
    if interface_style(ctx) == "ros2":
        _list_ros2(only or ["msg", "srv", "action"], interface_paths, as_json)
        return
    if only:
        raise RostoolError(
            "msg list -m/-s/-a apply to ROS 2 only (add --ros2); on ROS 1 see `rostool srv list`"
        )

    names = interfaces(interface_paths).message_names()
    if as_json:
        print_json(names)
    else:
        click.echo("\n".join(names))


def _list_ros2(kinds: list[str], interface_paths: tuple[str, ...], as_json: bool) -> None:
    from rostool.interfaces.describe_ros2 import Ros2Interfaces, list_sections

    catalog = Ros2Interfaces(interface_paths)
    if as_json:
        keys = {"msg": "messages", "srv": "services", "action": "actions"}
        print_json({keys[kind]: catalog.names(kind) for kind in kinds})
    else:
        click.echo("\n".join(list_sections(catalog, kinds)))


@msg.command("md5")
@click.argument("type_name", metavar="TYPE")
@interfaces_option
@click.pass_context
def md5(ctx: click.Context, type_name: str, interface_paths: tuple[str, ...]) -> None:
    """Print the md5sum of a message type (what ROS 1 peers compare).

    ROS 2 has no md5sums: on ROS 2 it prints the type's RIHS01 hash (REP 2016), what ROS 2 compares.

    \b
    Examples:
      rostool msg md5 std_msgs/String      # 992ce8a1687cec8c8bd883ec73ca41d1
      rostool --ros2 msg md5 std_msgs/msg/String      # RIHS01_df668c74...
    """
    from rostool.interfaces.sources import interfaces

    if interface_style(ctx, type_name) == "ros2":
        from rostool.interfaces.describe_ros2 import Ros2Interfaces

        click.echo(Ros2Interfaces(interface_paths).type_hash(type_name))
        return

    click.echo(interfaces(interface_paths).md5(type_name))
