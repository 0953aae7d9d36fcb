"""`rostool param`: list, get, set, delete, dump, load (rosparam's forms, typed YAML values)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from rostool.commands._common import json_option, live_graph, print_json, ros_version
from rostool.errors import RostoolError


@click.group()
def param() -> None:
    """Read and write the parameter server (like rosparam).

    \b
    Examples:
      rostool param set /wheel_radius 0.05
      rostool param get /wheel_radius
      rostool param dump params.yaml
      rostool param load params.yaml
      rostool --ros2 param get /talker use_sim_time     # ROS 2: NODE then PARAM
      rostool --ros2 param dump /talker > talker.yaml
    """


def _yaml_text(value: Any) -> str:
    """YAML of a value as rosparam writes it; PyYAML's document-end marker after scalars is dropped."""
    import yaml

    text = yaml.safe_dump(value, default_flow_style=False)
    return text[:-5] if text.endswith("\n...\n") else text


@param.command("list")
@click.argument("namespace", default="/")
@json_option
@click.pass_context
def list_params(ctx: click.Context, namespace: str, as_json: bool) -> None:
    """List parameter names, optionally only under NAMESPACE.

    \b
    Example:
      rostool param list /robot
    """
    with live_graph(ctx) as graph:
        if graph.ros_version == 2:
            _list_ros2(graph, None if namespace == "/" else namespace, as_json)
            return
        prefix = graph.resolve(namespace)
        names = [n for n in graph.param_names() if prefix == "/" or n == prefix or n.startswith(prefix + "/")]
    if as_json:
        print_json(names)
    else:
        for name in names:
            click.echo(name)


def _list_ros2(graph: Any, node: str | None, as_json: bool) -> None:
    """ros2 param list's forms: one node's names, or every node's under its name."""
    from rostool.graph.ros2.params import ParameterClient

    if node is not None:
        names = ParameterClient(graph, node).names()
        if as_json:
            print_json(names)
        else:
            click.echo("\n".join(f"  {n}" for n in names))
        return
    found: dict[str, list[str]] = {}
    for node_name in graph.node_names():
        try:
            found[node_name] = ParameterClient(graph, node_name, timeout=2.0).names()
        except RostoolError:
            continue  # a node without parameter services
    if as_json:
        print_json(found)
        return
    for node_name, names in found.items():
        click.echo(f"{node_name}:\n" + "\n".join(f"  {n}" for n in names))


def _ros2_only_args(graph: Any, extra: str | None, usage: str) -> None:
    if graph.ros_version == 2 and extra is None:
        raise RostoolError(f"ROS 2 parameters belong to a node: {usage}")
    if graph.ros_version != 2 and extra is not None:
        raise RostoolError(f"too many arguments for a ROS 1 parameter ({usage} is the ROS 2 form)")


@param.command("get")
@click.argument("name")
@click.argument("param_name", required=False, metavar="[PARAM]")
@json_option
@click.pass_context
def get(ctx: click.Context, name: str, param_name: str | None, as_json: bool) -> None:
    """Print a parameter (a namespace prints as a YAML mapping).

    \b
    Example:
      rostool param get /rosdistro
    """
    with live_graph(ctx) as graph:
        _ros2_only_args(graph, param_name, "rostool param get NODE PARAM")
        if param_name is not None:
            _get_ros2(graph, name, param_name, as_json)
            return
        value = graph.get_param(name)
    if as_json:
        print_json(value)
    else:
        click.echo(_yaml_text(value))  # rosparam get adds a newline after the YAML, so do we


def _get_ros2(graph: Any, node: str, name: str, as_json: bool) -> None:
    from rostool.graph.ros2.params import NOT_SET, ParameterClient, describe_value, to_python

    value = ParameterClient(graph, node).get(name)
    if int(value.type) == NOT_SET:
        raise RostoolError(f"parameter {name} is not set on node {graph.resolve(node)}")
    if as_json:
        print_json(to_python(value))
    else:
        click.echo(describe_value(value))


@param.command("set", context_settings={"ignore_unknown_options": True})
@click.argument("name")
@click.argument("value")
@click.argument("ros2_value", required=False, metavar="[VALUE2]")
@click.option("-t", "--textfile", is_flag=True, help="VALUE is a file whose text becomes a string parameter.")
@click.pass_context
def set_(ctx: click.Context, name: str, value: str, ros2_value: str | None, textfile: bool) -> None:
    """Set a parameter; VALUE is YAML, so 0.05 is a float, 5 an int, true a bool, [1, 2] a list.

    \b
    Examples:
      rostool param set /wheel_radius 0.05
      rostool param set /robot "{name: r2, wheels: 4}"
      rostool param set /label "'42'"        # the string "42"
    """
    from rostool.interfaces.values import parse_yaml

    with live_graph(ctx) as graph:
        _ros2_only_args(graph, ros2_value, "rostool param set NODE PARAM VALUE")
        if ros2_value is not None:
            node, name, value = name, value, ros2_value
        parsed = _read_text(value) if textfile else parse_yaml(value, f"the value of {name}")
        if ros2_value is not None:
            _set_ros2(graph, node, name, parsed)
            return
        _set_checked(graph, name, parsed)


def _set_ros2(graph: Any, node: str, name: str, value: Any) -> None:
    from rostool.graph.ros2.params import ParameterClient

    ok, reason = ParameterClient(graph, node).set(name, value)
    if not ok:
        raise RostoolError(f"setting parameter {name} on {graph.resolve(node)} failed: {reason or 'refused'}")
    click.echo("Set parameter successful")


@param.command("describe")
@click.argument("node")
@click.argument("names", nargs=-1, required=True, metavar="PARAM...")
@json_option
@click.pass_context
def describe(ctx: click.Context, node: str, names: tuple[str, ...], as_json: bool) -> None:
    """ROS 2: show a parameter's type, description and constraints.

    \b
    Example:
      rostool --ros2 param describe /talker use_sim_time
    """
    from rostool.graph.ros2.params import TYPE_NAMES, ParameterClient

    with live_graph(ctx) as graph:
        if graph.ros_version != 2:
            raise RostoolError("param describe applies to ROS 2 nodes (ROS 1 parameters have no descriptors)")
        client = ParameterClient(graph, node)
        found = [client.describe(name) for name in names]
    rows = [
        {"name": d.name, "type": TYPE_NAMES.get(int(d.type), str(d.type)), "description": d.description,
         "additional_constraints": d.additional_constraints, "read_only": bool(d.read_only)}
        for d in found
    ]  # fmt: skip
    if as_json:
        print_json(rows)
        return
    for row in rows:
        lines = [f"Parameter name: {row['name']}", f"  Type: {row['type']}"]
        if row["description"]:
            lines.append(f"  Description: {row['description']}")
        lines.append("  Constraints:")
        if row["read_only"]:
            lines.append("    Read only: true")
        if row["additional_constraints"]:
            lines.append(f"    {row['additional_constraints']}")
        click.echo("\n".join(lines))


def _read_text(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError as err:
        raise RostoolError(f"cannot read {path}: {err.strerror}") from err


def _set_checked(graph: Any, name: str, value: Any) -> None:
    """Set like rosparam: a mapping updates the namespace key by key instead of replacing it."""
    if isinstance(value, dict):
        for key, item in value.items():
            _set_checked(graph, _join(name, str(key)), item)
        return
    try:
        graph.set_param(name, value)
    except OverflowError as err:
        raise RostoolError(f"{name}: integers must fit in 32 bits on the ROS 1 parameter server") from err
    except TypeError as err:
        raise RostoolError(f"{name}: this value cannot be stored on the parameter server ({err})") from err


@param.command("delete")
@click.argument("name")
@click.argument("param_name", required=False, metavar="[PARAM]")
@click.pass_context
def delete(ctx: click.Context, name: str, param_name: str | None) -> None:
    """Delete a parameter (or a whole namespace). ROS 2: NODE then PARAM.

    \b
    Examples:
      rostool param delete /wheel_radius
      rostool --ros2 param delete /talker my_param
    """
    with live_graph(ctx) as graph:
        _ros2_only_args(graph, param_name, "rostool param delete NODE PARAM")
        if param_name is not None:
            _delete_ros2(graph, name, param_name)
            return
        graph.delete_param(name)


def _delete_ros2(graph: Any, node: str, name: str) -> None:
    from rostool.graph.ros2.params import ParameterClient

    ok, reason = ParameterClient(graph, node).delete(name)
    if not ok:
        raise RostoolError(
            f"deleting parameter {name} on {graph.resolve(node)} failed: {reason or 'refused'}"
        )
    click.echo("Deleted parameter successfully" + (f": {reason}" if reason else ""))


def _is_ros2(ctx: click.Context) -> bool:
    """The version decides what dump's and load's arguments mean, so it is chosen before reading files."""
    from rostool.graph import select_ros_version

    return select_ros_version(ros_version(ctx)) == 2


@param.command("dump")
@click.argument("file", metavar="FILE|NODE")
@click.argument("namespace", required=False, metavar="[NAMESPACE|FILE]")
@json_option
@click.pass_context
def dump(ctx: click.Context, file: str, namespace: str | None, as_json: bool) -> None:
    """Write parameters (all, or under NAMESPACE) to a YAML FILE ("-" for stdout).

    ROS 2: every parameter of NODE, printed (or written to FILE) in the parameter file layout that
    `param load` and a node's --params-file read.

    \b
    Examples:
      rostool param dump params.yaml
      rostool param dump robot.yaml /robot
      rostool --ros2 param dump /talker > talker.yaml
    """
    if _is_ros2(ctx):
        _dump_ros2(ctx, node=file, target=namespace or "-", as_json=as_json)
        return
    with live_graph(ctx) as graph:
        value = graph.get_param(namespace or "/")
    _write(file, _json_text(value) if as_json else _yaml_text(value).rstrip("\n") + "\n")


def _dump_ros2(ctx: click.Context, node: str, target: str, as_json: bool) -> None:
    from rostool.graph.ros2.params import ParameterClient, dump_document

    with live_graph(ctx) as graph:
        document = dump_document(ParameterClient(graph, node))
    if as_json:
        _write(target, _json_text(document))
    elif target == "-":
        click.echo(_yaml_text(document))  # ros2 param dump prints the YAML and then a blank line
    else:
        _write(target, _yaml_text(document))


def _json_text(value: Any) -> str:
    from rostool.output.json_text import dumps

    return dumps(value) + "\n"


def _write(file: str, text: str) -> None:
    if file == "-":
        click.echo(text, nl=False)
        return
    target = Path(file)
    temporary = target.with_name(f".{target.name}.tmp")
    try:
        temporary.write_text(text)
        temporary.replace(target)  # never leaves a half-written file behind
    except OSError as err:
        temporary.unlink(missing_ok=True)
        raise RostoolError(f"cannot write {file}: {err.strerror}") from err


@param.command("load")
@click.argument("file", metavar="FILE|NODE")
@click.argument("namespace", required=False, metavar="[NAMESPACE|FILE]")
@click.option(
    "--no-use-wildcard", is_flag=True, help="ROS 2: skip the file's '/**' section, load only the node's own."
)
@click.pass_context
def load(ctx: click.Context, file: str, namespace: str | None, no_use_wildcard: bool) -> None:
    """Set parameters from a YAML FILE ("-" for stdin), under NAMESPACE.

    ROS 2: NODE then FILE, a parameter file as `param dump` writes it; the node's own section and the
    '/**' section for every node are loaded, the node's own winning.

    \b
    Examples:
      rostool param load params.yaml /robot
      rostool --ros2 param load /talker talker.yaml
      rostool --ros2 param load /talker common.yaml --no-use-wildcard
    """
    if _is_ros2(ctx):
        if namespace is None:
            raise RostoolError("ROS 2 parameters belong to a node: rostool param load NODE FILE")
        if _load_ros2(ctx, node=file, file=namespace, use_wildcard=not no_use_wildcard):
            ctx.exit(1)
        return
    if no_use_wildcard:
        raise RostoolError("--no-use-wildcard applies to ROS 2 parameter files (rostool --ros2 param load)")
    _load_ros1(ctx, file, namespace or "/")


def _read_document(file: str) -> Any:
    from rostool.interfaces.values import parse_yaml

    text = sys.stdin.read() if file == "-" else _read_text(file)
    return parse_yaml(text, file)


def _load_ros1(ctx: click.Context, file: str, namespace: str) -> None:
    value = _read_document(file)
    with live_graph(ctx) as graph:
        prefix = graph.resolve(namespace)
        if isinstance(value, dict):
            _set_checked(graph, prefix, value)
        elif value is None:
            raise RostoolError(f"{file} holds no parameters")
        else:
            if prefix == "/":
                raise RostoolError(f"{file} holds a single value; give a NAMESPACE to store it under")
            _set_checked(graph, prefix, value)


def _load_ros2(ctx: click.Context, node: str, file: str, use_wildcard: bool) -> int:
    """ros2 param load: one result line per parameter, failures on stderr; returns how many failed."""
    from rostool.graph.ros2.params import ParameterClient, file_parameters, load_fields

    document = _read_document(file)
    with live_graph(ctx) as graph:
        client = ParameterClient(graph, node)
        parameters = file_parameters(document, client.node, use_wildcard, file)
        results = client.set_fields(load_fields(client, parameters, file))
    for name, ok, reason in results:
        line = f"Set parameter {name} {'successful' if ok else 'failed'}" + (f": {reason}" if reason else "")
        click.echo(line, err=not ok)
    return sum(not ok for _, ok, _ in results)


def _join(namespace: str, key: str) -> str:
    if key.startswith("/"):
        return key
    return namespace.rstrip("/") + "/" + key
