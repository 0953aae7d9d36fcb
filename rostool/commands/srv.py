"""`rostool srv`: show, list, md5 (rossrv's forms) for service types from sources and built-ins; on ROS 2
(--ros2, ROS_VERSION=2 or a `pkg/srv/T` name) show and list in `ros2 interface`'s forms."""

from __future__ import annotations

import click

from rostool.commands._common import interface_style, interfaces_option, json_option, print_json


@click.group()
def srv() -> None:
    """Show service types (like rossrv), from source trees or built in, no catkin build needed.

    \b
    Examples:
      rostool srv show sum_two_numbers/SumTwoInts --interfaces ~/catkin_ws
      rostool srv show Trigger
      rostool srv list
      rostool --ros2 srv show example_interfaces/srv/AddTwoInts
    """


def srv_text(paths: tuple[str, ...], type_name: str) -> str:
    """Request lines, `---`, response lines: what `rossrv show` prints."""
    from rostool.interfaces.sources import interfaces
    from rostool.interfaces.srv import load_service

    catalog = interfaces(paths)
    found = load_service(catalog, type_name)
    lines = [*catalog.show_lines(found.request.name), "---", *catalog.show_lines(found.response.name)]
    return "\n".join(lines) + "\n"


@srv.command("show")
@click.argument("type_name", metavar="TYPE")
@click.option("-r", "--raw", is_flag=True, help="Print the .srv text as written, comments included.")
@interfaces_option
@click.pass_context
def show(ctx: click.Context, type_name: str, raw: bool, interface_paths: tuple[str, ...]) -> None:
    """Print the request and response fields of a service type (nested types expanded).

    TYPE is pkg/Type, or a bare Type to show it from every package that has one. On ROS 2 (--ros2,
    ROS_VERSION=2 or a pkg/srv/Type name) it prints what `ros2 interface show --no-comments` does.

    \b
    Examples:
      rostool srv show sum_two_numbers/SumTwoInts
      rostool srv show std_srvs/SetBool --raw
      rostool --ros2 srv show example_interfaces/srv/AddTwoInts
    """
    from rostool.errors import RostoolError
    from rostool.interfaces.sources import interfaces
    from rostool.interfaces.srv import load_service, service_names

    if interface_style(ctx, type_name) == "ros2":
        from rostool.interfaces.describe_ros2 import show_text

        click.echo(show_text(type_name, "srv", interface_paths, raw), nl=False)
        return

    if "/" in type_name:
        found = [type_name]
    else:
        found = [n for n in service_names(interfaces(interface_paths)) if n.endswith(f"/{type_name}")]
        if not found:
            raise RostoolError(f"unknown service type {type_name!r} (see `rostool srv list`)")
    for name in found:
        if "/" not in type_name:
            click.echo(f"[{name}]:")
        if raw:
            click.echo(load_service(interfaces(interface_paths), name).text)
        else:
            click.echo(srv_text(interface_paths, name))


@srv.command("list")
@interfaces_option
@json_option
@click.pass_context
def list_types(ctx: click.Context, interface_paths: tuple[str, ...], as_json: bool) -> None:
    """List the service types rostool finds (source trees and built-ins).

    On ROS 2 it prints what `ros2 interface list -s` does.

    \b
    Examples:
      rostool srv list --interfaces ~/catkin_ws/src
      rostool --ros2 srv list
    """
    from rostool.interfaces.sources import interfaces
    from rostool.interfaces.srv import service_names

    if interface_style(ctx) == "ros2":
        from rostool.interfaces.describe_ros2 import Ros2Interfaces, list_sections

        catalog = Ros2Interfaces(interface_paths)
        if as_json:
            print_json(catalog.names("srv"))
        else:
            click.echo("\n".join(list_sections(catalog, ["srv"])))
        return

    names = service_names(interfaces(interface_paths))
    if as_json:
        print_json(names)
    else:
        click.echo("\n".join(names))


@srv.command("md5")
@click.argument("type_name", metavar="TYPE")
@interfaces_option
@click.pass_context
def md5(ctx: click.Context, type_name: str, interface_paths: tuple[str, ...]) -> None:
    """Print the md5sum of a service type (what a ROS 1 service and its callers compare).

    \b
    Example:
      rostool srv md5 std_srvs/Trigger      # 937c9679a518e3a18d831e57125ea522
    """
    from rostool.errors import RostoolError
    from rostool.interfaces.sources import interfaces
    from rostool.interfaces.srv import load_service

    if interface_style(ctx, type_name) == "ros2":
        raise RostoolError(
            "ROS 2 services have no md5sum; `rostool --ros2 msg md5 TYPE` prints a message type's RIHS01 hash"
        )

    click.echo(load_service(interfaces(interface_paths), type_name).md5sum)
