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
    from rostool.graph.ros1.names import resolve

    prefix = resolve(namespace)
    with live_graph(ctx) as graph:
        names = [n for n in graph.param_names() if prefix == "/" or n == prefix or n.startswith(prefix + "/")]
    if as_json:
        print_json(names)
    else:
        for name in names:
            click.echo(name)


@param.command("get")
@click.argument("name")
@json_option
@click.pass_context
def get(ctx: click.Context, name: str, as_json: bool) -> None:
    """Print a parameter (a namespace prints as a YAML mapping).

    \b
    Example:
      rostool param get /rosdistro
    """
    with live_graph(ctx) as graph:
        value = graph.get_param(name)
    if as_json:
        print_json(value)
    else:
        click.echo(_yaml_text(value))  # rosparam get adds a newline after the YAML, so do we


@param.command("set", context_settings={"ignore_unknown_options": True})
@click.argument("name")
@click.argument("value")
@click.option("-t", "--textfile", is_flag=True, help="VALUE is a file whose text becomes a string parameter.")
@click.pass_context
def set_(ctx: click.Context, name: str, value: str, textfile: bool) -> None:
    """Set a parameter; VALUE is YAML, so 0.05 is a float, 5 an int, true a bool, [1, 2] a list.

    \b
    Examples:
      rostool param set /wheel_radius 0.05
      rostool param set /robot "{name: r2, wheels: 4}"
      rostool param set /label "'42'"        # the string "42"
    """
    from rostool.interfaces.values import parse_yaml

    parsed = _read_text(value) if textfile else parse_yaml(value, f"the value of {name}")
    with live_graph(ctx) as graph:
        _set_checked(graph, name, parsed)


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
@click.pass_context
def delete(ctx: click.Context, name: str) -> None:
    """Delete a parameter (or a whole namespace).

    \b
    Example:
      rostool param delete /wheel_radius
    """
    with live_graph(ctx) as graph:
        graph.delete_param(name)


@param.command("dump")
@click.argument("file", type=click.Path(dir_okay=False, writable=True))
@click.argument("namespace", default="/")
@click.pass_context
def dump(ctx: click.Context, file: str, namespace: str) -> None:
    """Write parameters (all, or under NAMESPACE) to a YAML FILE ("-" for stdout).

    \b
    Example:
      rostool param dump params.yaml
    """
    with live_graph(ctx) as graph:
        value = graph.get_param(namespace)
    text = _yaml_text(value).rstrip("\n") + "\n"
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
@click.argument("file", type=click.Path(dir_okay=False))
@click.argument("namespace", default="/")
@click.pass_context
def load(ctx: click.Context, file: str, namespace: str) -> None:
    """Set parameters from a YAML FILE ("-" for stdin), under NAMESPACE.

    \b
    Example:
      rostool param load params.yaml /robot
    """
    from rostool.graph.ros1.names import resolve
    from rostool.interfaces.values import parse_yaml

    text = sys.stdin.read() if file == "-" else _read_text(file)
    value = parse_yaml(text, file)
    prefix = resolve(namespace)
    with live_graph(ctx) as graph:
        if isinstance(value, dict):
            _set_checked(graph, prefix, value)
        elif value is None:
            raise RostoolError(f"{file} holds no parameters")
        else:
            if prefix == "/":
                raise RostoolError(f"{file} holds a single value; give a NAMESPACE to store it under")
            _set_checked(graph, prefix, value)


def _join(namespace: str, key: str) -> str:
    if key.startswith("/"):
        return key
    return namespace.rstrip("/") + "/" + key
