"""`rostool interface`: list, package, packages, proto, show — `ros2 interface`'s verbs and output for the
ROS 2 types rostool knows (rosbags' distro store, its built-in services and actions, and .msg/.srv/.action
files under --interfaces, AMENT_PREFIX_PATH and the current workspace). No graph, no build."""

from __future__ import annotations

import sys

import click

from rostool.commands._common import interfaces_option, json_option, print_json
from rostool.errors import RostoolError

KINDS = ("msg", "srv", "action")


def kind_options(func: click.decorators.FC) -> click.decorators.FC:
    for flag, long, kind in (("-a", "--only-actions", "actions"), ("-s", "--only-srvs", "services"),
                             ("-m", "--only-msgs", "messages")):  # fmt: skip
        func = click.option(flag, long, long[2:].replace("-", "_"), is_flag=True, help=f"Only {kind}.")(func)
    return func


def _kinds(only_msgs: bool, only_srvs: bool, only_actions: bool) -> list[str]:
    chosen = [k for k, on in zip(KINDS, (only_msgs, only_srvs, only_actions), strict=True) if on]
    return chosen or list(KINDS)


@click.group()
def interface() -> None:
    """Show and list ROS 2 interface types (like ros2 interface), whatever ROS version is selected.

    Types come from rosbags' store for ROS_DISTRO (default jazzy), rostool's built-in services and
    actions, and .msg/.srv/.action files (--interfaces, AMENT_PREFIX_PATH, the current workspace).
    ROS 1 types: `rostool msg` and `rostool srv`.

    \b
    Examples:
      rostool interface show geometry_msgs/msg/Twist
      rostool interface list -m
      rostool interface package std_srvs
      rostool interface packages -a
      rostool interface proto geometry_msgs/msg/Point
      echo std_msgs/msg/String | rostool interface show -
    """


def _catalog(interface_paths: tuple[str, ...]) -> object:
    from rostool.interfaces.describe_ros2 import Ros2Interfaces

    return Ros2Interfaces(interface_paths)


def _names(catalog: object, kinds: list[str]) -> list[str]:
    return sorted(name for kind in kinds for name in catalog.names(kind))  # type: ignore[attr-defined]


def _check_known(catalog: object, type_name: str) -> None:
    """ros2 interface's words for a package or a type it does not know."""
    parts = type_name.strip().strip("/").split("/")
    if len(parts) != 3 or parts[1] not in KINDS:
        return  # left to the show functions (a bare or pkg/Type name)
    package, kind, name = parts
    known = _names(catalog, list(KINDS))
    if not any(n.startswith(f"{package}/") for n in known):
        raise RostoolError(f"Unknown package '{package}' (see `rostool interface packages`)")
    if f"{package}/{kind}/{name}" not in known:
        raise RostoolError(f"Interface '{kind}/{name}' not found in package '{package}'")


@interface.command("list")
@kind_options
@interfaces_option
@json_option
def list_interfaces(
    only_msgs: bool, only_srvs: bool, only_actions: bool, interface_paths: tuple[str, ...], as_json: bool
) -> None:
    """List every interface type, under Messages:, Services: and Actions: titles.

    \b
    Examples:
      rostool interface list
      rostool interface list -s
    """
    from rostool.interfaces.describe_ros2 import list_sections

    catalog = _catalog(interface_paths)
    kinds = _kinds(only_msgs, only_srvs, only_actions)
    if as_json:
        keys = {"msg": "messages", "srv": "services", "action": "actions"}
        print_json({keys[k]: catalog.names(k) for k in kinds})  # type: ignore[attr-defined]
        return
    click.echo("\n".join(list_sections(catalog, kinds)))  # type: ignore[arg-type]


@interface.command("package")
@click.argument("package_name", metavar="PACKAGE")
@kind_options
@interfaces_option
@json_option
def package(
    package_name: str, only_msgs: bool, only_srvs: bool, only_actions: bool, interface_paths: tuple[str, ...],
    as_json: bool,
) -> None:  # fmt: skip
    """List the interface types of one package (pkg/msg/Type, pkg/srv/Type, pkg/action/Type).

    \b
    Examples:
      rostool interface package std_msgs
      rostool interface package example_interfaces -s
    """
    catalog = _catalog(interface_paths)
    every = _names(catalog, list(KINDS))
    if not any(n.startswith(f"{package_name}/") for n in every):
        raise RostoolError(f"Unknown package '{package_name}' (see `rostool interface packages`)")
    found = [n for n in _names(catalog, _kinds(only_msgs, only_srvs, only_actions))
             if n.startswith(f"{package_name}/")]  # fmt: skip
    if as_json:
        print_json(found)
    elif found:
        click.echo("\n".join(found))


@interface.command("packages")
@kind_options
@interfaces_option
@json_option
def packages(
    only_msgs: bool, only_srvs: bool, only_actions: bool, interface_paths: tuple[str, ...], as_json: bool
) -> None:
    """List the packages that define interface types (-m/-s/-a: of that kind).

    \b
    Examples:
      rostool interface packages
      rostool interface packages -a
    """
    catalog = _catalog(interface_paths)
    found = sorted({n.split("/")[0] for n in _names(catalog, _kinds(only_msgs, only_srvs, only_actions))})
    if as_json:
        print_json(found)
    else:
        click.echo("\n".join(found))


def _read_type_name(type_name: str) -> str:
    if type_name != "-":
        return type_name
    given = sys.stdin.readline().strip()
    if not given:
        raise RostoolError("interface show -: no type name on stdin (e.g. `echo std_msgs/msg/String | ...`)")
    return given


@interface.command("show")
@click.argument("type_name", metavar="TYPE|-")
@click.option("--all-comments", is_flag=True, help="Also the comments of nested types.")
@click.option("--no-comments", is_flag=True, help="No comments and no blank lines.")
@interfaces_option
def show(type_name: str, all_comments: bool, no_comments: bool, interface_paths: tuple[str, ...]) -> None:
    """Print a message, service or action type with its nested types expanded ("-": the name is read from
    stdin), with the definition file's comments as ros2 interface show prints them. Types rostool knows
    only from rosbags' store (no file) print without comments, as --no-comments.

    \b
    Examples:
      rostool interface show geometry_msgs/msg/PoseStamped
      rostool interface show example_interfaces/srv/AddTwoInts
      rostool interface show test_msgs/action/Fibonacci --interfaces ~/ros2_ws/src
    """
    from rostool.interfaces.describe_ros2 import commented_text, kind_of, show_text

    if all_comments and no_comments:
        raise RostoolError("give --all-comments or --no-comments, not both")
    name = _read_type_name(type_name)
    _check_known(_catalog(interface_paths), name)
    kind = kind_of(name) or "msg"
    text = None if no_comments else commented_text(name, kind, interface_paths, all_comments)
    click.echo(text if text is not None else show_text(name, kind, interface_paths), nl=False)


@interface.command("proto")
@click.argument("type_name", metavar="TYPE")
@click.option("--no-quotes", is_flag=True, help="Print the YAML without the outer double quotes.")
@interfaces_option
def proto(type_name: str, no_quotes: bool, interface_paths: tuple[str, ...]) -> None:
    """Print a message type's default value as YAML, ready to edit for `topic pub` (in double quotes, as
    ros2 interface proto prints it).

    \b
    Examples:
      rostool interface proto geometry_msgs/msg/Twist
      rostool interface proto --no-quotes geometry_msgs/msg/Twist > twist.yaml
    """
    from rostool.interfaces.fill import build_message
    from rostool.output.yaml_text import to_yaml

    catalog = _catalog(interface_paths)
    _check_known(catalog, type_name)
    store_name = catalog.message(type_name)  # type: ignore[attr-defined]
    types = catalog.types  # type: ignore[attr-defined]
    message = build_message(types.store, store_name, types.with_defaults(store_name, {}))
    text = to_yaml(message, "ros2") + "\n"
    click.echo(text if no_quotes else f'"{text}"')
