"""`rostool param`: list, get, set, delete, dump, load (rosparam's forms, typed YAML values)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from rostool.commands._common import json_option, live_graph, print_json
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
        if graph.style == "ros2":
            _list_ros2(graph, None if namespace == "/" else namespace, as_json)
            return
        names = graph.parameters(namespace).names()
    if as_json:
        print_json(names)
    else:
        for name in names:
            click.echo(name)


def _list_ros2(graph: Any, node: str | None, as_json: bool) -> None:
    """ros2 param list's forms: one node's names, or every node's under its name."""
    if node is not None:
        names = graph.parameters(node).names()
        if as_json:
            print_json(names)
        else:
            click.echo("\n".join(f"  {n}" for n in names))
        return
    found: dict[str, list[str]] = {}
    for node_name in graph.node_names():
        try:
            found[node_name] = graph.parameters(node_name, timeout=2.0).names()
        except RostoolError:
            continue  # a node without parameter services
    if as_json:
        print_json(found)
        return
    for node_name, names in found.items():
        click.echo(f"{node_name}:\n" + "\n".join(f"  {n}" for n in names))


def _ros2_only_args(graph: Any, extra: str | None, usage: str) -> None:
    if graph.style == "ros2" and extra is None:
        raise RostoolError(f"ROS 2 parameters belong to a node: {usage}")
    if graph.style != "ros2" and extra is not None:
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
        node, name = (None, name) if param_name is None else (name, param_name)
        value, text = graph.parameters(node).show(name)
    if as_json:
        print_json(value)
    else:
        click.echo(text)  # rosparam get adds a newline after the YAML, so do we


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
        node = None
        if ros2_value is not None:
            node, name, value = name, value, ros2_value
        parsed = _read_text(value) if textfile else parse_yaml(value, f"the value of {name}")
        params = graph.parameters(node)
        ok, reason = params.set(name, parsed)
        if not ok:
            raise RostoolError(f"setting parameter {name} on {params.node} failed: {reason or 'refused'}")
        if node is not None:
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
    with live_graph(ctx) as graph:
        params = graph.parameters(node)
        rows = [params.descriptor(name) for name in names]
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
        node, name = (None, name) if param_name is None else (name, param_name)
        params = graph.parameters(node)
        ok, reason = params.delete(name)
        if not ok:
            raise RostoolError(f"deleting parameter {name} on {params.node} failed: {reason or 'refused'}")
        if node is not None:
            click.echo("Deleted parameter successfully" + (f": {reason}" if reason else ""))


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
    from rostool.output.yaml_text import param_yaml

    with live_graph(ctx) as graph:
        ros2 = graph.style == "ros2"
        node, target = (file, namespace or "-") if ros2 else (namespace, file)
        document = graph.parameters(node).dump()
    if as_json:
        _write(target, _json_text(document))
    elif ros2 and target == "-":
        click.echo(param_yaml(document))  # ros2 param dump prints the YAML and then a blank line
    else:
        _write(target, param_yaml(document) if ros2 else param_yaml(document).rstrip("\n") + "\n")


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
    with live_graph(ctx) as graph:
        node = namespace or "/"
        if graph.style == "ros2":
            if namespace is None:
                raise RostoolError("ROS 2 parameters belong to a node: rostool param load NODE FILE")
            node, file = file, namespace
        elif no_use_wildcard:
            raise RostoolError(
                "--no-use-wildcard applies to ROS 2 parameter files (rostool --ros2 param load)"
            )
        results = graph.parameters(node).load(_read_document(file), not no_use_wildcard, file)
    for name, ok, reason in results:
        line = f"Set parameter {name} {'successful' if ok else 'failed'}" + (f": {reason}" if reason else "")
        click.echo(line, err=not ok)
    if not all(ok for _, ok, _ in results):
        ctx.exit(1)


def _read_document(file: str) -> Any:
    from rostool.interfaces.values import parse_yaml

    text = sys.stdin.read() if file == "-" else _read_text(file)
    return parse_yaml(text, file)
