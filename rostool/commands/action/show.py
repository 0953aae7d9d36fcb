"""`rostool action show`: an action type's goal, result and feedback fields (on ROS 2 as ros2 interface
show)."""

from __future__ import annotations

import click

from rostool.commands._common import interface_style, interfaces_option


@click.command("show")
@click.argument("type_name", metavar="TYPE")
@click.option("-r", "--raw", is_flag=True, help="Print the .action text as written, comments included.")
@interfaces_option
@click.pass_context
def show(ctx: click.Context, type_name: str, raw: bool, interface_paths: tuple[str, ...]) -> None:
    """Print the goal, result and feedback fields of an action type.

    On ROS 2 (--ros2, ROS_VERSION=2 or a pkg/action/Type name) it prints what `ros2 interface show
    --no-comments` does.

    \b
    Examples:
      rostool action show robot_navigation_pkg/MoveToPoint --interfaces ~/catkin_ws
      rostool action show actionlib/TwoInts
      rostool --ros2 action show example_interfaces/action/Fibonacci
    """
    from rostool.interfaces.action import load_action
    from rostool.interfaces.describe_ros2 import show_text
    from rostool.interfaces.sources import interfaces

    if interface_style(ctx, type_name) == "ros2":
        click.echo(show_text(type_name, "action", interface_paths, raw), nl=False)
        return

    catalog = interfaces(interface_paths)
    found = load_action(catalog, type_name)
    if raw and not found.origin.startswith("built-in"):
        with open(found.origin, encoding="utf-8") as source:
            click.echo(source.read(), nl=False)
        return
    lines: list[str] = []
    for part in (found.goal, found.result, found.feedback):
        if lines:
            lines.append("---")
        lines.extend(catalog.show_lines(part.name))
    click.echo("\n".join(lines) + "\n")
