"""`rostool param`: list, get, set, delete, dump, load (rosparam's forms, typed YAML values); on ROS 2 also
describe, in ros2 param's forms and output (NODE first, --include-hidden-nodes, --timeout)."""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.errors import RostoolError
from rostool.interfaces.names import hidden_name

hidden_nodes_option = click.option(
    "--include-hidden-nodes", "include_hidden", is_flag=True, help="ROS 2: hidden nodes (_name) count too."
)
node_timeout_option = click.option(
    "--timeout", "node_timeout", type=click.FloatRange(min=0), default=1.0, show_default=True, metavar="S",
    help="ROS 2: seconds to wait for NODE to appear.",
)  # fmt: skip


def ros2_param_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """The options every ROS 2 param verb takes: hidden nodes, --timeout, and ros2cli's ignored ones."""
    for option in (ignored_ros2_options("no_daemon", "spin_time", "use_sim_time"), node_timeout_option,
                   hidden_nodes_option):  # fmt: skip
        func = option(func)
    return func


def _ros2_only(graph: Any, **given: Any) -> None:
    """Refuse ros2 param's flags on a ROS 1 graph (rosparam has none of them)."""
    used = [name for name, value in given.items() if value]
    if graph.style != "ros2" and used:
        flags = ", ".join("--" + name.replace("_", "-") for name in used)
        raise RostoolError(f"{flags} apply to ROS 2 parameters only (rostool --ros2 param ...)")


def _find_node(graph: Any, node: str, include_hidden: bool, timeout: float) -> str:
    """ros2 param's node check: a hidden node needs --include-hidden-nodes; wait up to TIMEOUT for it."""
    resolved = graph.resolve(node)
    if hidden_name(resolved) and not include_hidden:
        raise RostoolError(f"Node not found: {resolved} is hidden (add --include-hidden-nodes)")
    deadline = time.monotonic() + timeout
    while resolved not in graph.node_names():
        if time.monotonic() >= deadline:
            raise RostoolError(f"Node not found: {resolved} (see `rostool node list`)")
        time.sleep(0.2)
    return resolved


def _ros2_nodes(graph: Any, include_hidden: bool) -> list[str]:
    """Each node name once (nodes may share a name; their parameter services are the same names)."""
    return [n for n in dict.fromkeys(graph.node_names()) if include_hidden or not hidden_name(n)]


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

    Flags and output follow the selected ROS version: rosparam's under ROS 1, ros2 param's under ROS 2
    (NODE first, --include-hidden-nodes, --timeout). --json works in both. ros2cli flags with no meaning
    here (--spin-time, -s/--use-sim-time) are accepted and ignored.
    """


@param.command("list")
@click.argument("namespace", required=False, metavar="[NAMESPACE|NODE]")
@click.option(
    "--param-prefixes",
    "prefixes",
    multiple=True,
    metavar="PREFIX",
    help="ROS 2: only parameters named PREFIX or PREFIX.* (repeatable).",
)
@click.option("-t", "--param-type", "with_types", is_flag=True, help="ROS 2: each name with its type.")
@click.option("--filter", "pattern", metavar="REGEX", help="ROS 2: only names matching REGEX.")
@click.option("--service-timeout", type=click.FloatRange(min=0), hidden=True)
@ros2_param_options
@json_option
@click.pass_context
def list_params(
    ctx: click.Context, namespace: str | None, prefixes: tuple[str, ...], with_types: bool,
    pattern: str | None, service_timeout: float | None, include_hidden: bool, node_timeout: float,
    as_json: bool,
) -> None:  # fmt: skip
    """List parameter names, optionally only under NAMESPACE (ROS 2: of NODE, or of every node).

    \b
    Examples:
      rostool param list /robot
      rostool --ros2 param list /talker -t --filter 'use_.*'
      rostool --ros2 param list --param-prefixes qos_overrides
    """
    try:
        regex = re.compile(pattern) if pattern else None
    except re.error as err:
        raise RostoolError(f"--filter {pattern!r} is not a regular expression: {err}") from err
    with live_graph(ctx) as graph:
        _ros2_only(graph, param_prefixes=prefixes, param_type=with_types, filter=pattern,
                   include_hidden_nodes=include_hidden)  # fmt: skip
        if graph.style == "ros2":
            wait = max(node_timeout, service_timeout or 0.0)
            node = None if namespace in (None, "/") else _find_node(graph, namespace, include_hidden, wait)
            _list_ros2(graph, node, _Selection(prefixes, regex, with_types), include_hidden, as_json)
            return
        names = graph.parameters(namespace or "/").names()
    if as_json:
        print_json(names)
    else:
        for name in names:
            click.echo(name)


class _Selection:
    """ros2 param list's --param-prefixes, --filter and --param-type."""

    def __init__(self, prefixes: tuple[str, ...], regex: re.Pattern[str] | None, with_types: bool) -> None:
        self.prefixes, self.regex, self.with_types = prefixes, regex, with_types

    def names(self, params: Any) -> list[str]:
        names = params.names()
        if self.prefixes:  # as rclpy's list_parameters: the prefix itself or PREFIX.anything
            names = [n for n in names if any(n == p or n.startswith(p + ".") for p in self.prefixes)]
        return [n for n in names if self.regex is None or self.regex.match(n)]

    def lines(self, params: Any, names: list[str]) -> list[str]:
        if not self.with_types:
            return [f"  {n}" for n in names]
        return [f"  {n} (type: {params.descriptor(n)['type']})" for n in names]


def _list_ros2(
    graph: Any, node: str | None, selection: _Selection, include_hidden: bool, as_json: bool
) -> None:
    """ros2 param list's forms: one node's names, or every node's under its name."""
    found: dict[str, tuple[Any, list[str]]] = {}
    for node_name in [node] if node else _ros2_nodes(graph, include_hidden):
        try:
            params = graph.parameters(node_name, timeout=2.0)
            found[node_name] = (params, selection.names(params))
        except RostoolError:
            if node:
                raise
            continue  # a node without parameter services
    if as_json:
        plain = {n: names for n, (_, names) in found.items()}
        print_json(plain[node] if node else plain)
        return
    for node_name, (params, names) in found.items():
        if node is None:
            click.echo(f"{node_name}:")
        if names:
            click.echo("\n".join(selection.lines(params, names)))


def _ros2_only_args(graph: Any, extra: str | None, usage: str) -> None:
    if graph.style == "ros2" and extra is None:
        raise RostoolError(f"ROS 2 parameters belong to a node: {usage}")
    if graph.style != "ros2" and extra is not None:
        raise RostoolError(f"too many arguments for a ROS 1 parameter ({usage} is the ROS 2 form)")


# Jazzy's ros2 param get prints integer and double arrays as lists (numpy's tolist()), byte arrays as
# rclpy's list of single bytes (a byte may arrive signed)
_ROS2_ARRAYS: dict[str, Callable[[Any], str]] = {
    "Integer values are": lambda v: repr([int(x) for x in v]),
    "Double values are": lambda v: repr([float(x) for x in v]),
    "Byte values are": lambda v: repr([bytes([x & 0xFF]) if isinstance(x, int) else bytes(x) for x in v]),
}


def _get_text(value: Any, text: str, hide_type: bool) -> str:
    """ros2 param get's line (`Integer values are: [1, 2]`), or only the value (--hide-type)."""
    label, sep, shown = text.partition(": ")
    if sep and label in _ROS2_ARRAYS:
        shown = _ROS2_ARRAYS[label](value)
    if not sep:
        return "None" if hide_type else text
    return shown if hide_type else f"{label}: {shown}"


def _show_ros2(graph: Any, node: str, name: str, hide_type: bool) -> tuple[Any, str]:
    params = graph.parameters(node)
    try:
        value, text = params.show(name)
    except RostoolError:
        try:
            declared_unset = params.descriptor(name)["type"] == "not set"
        except RostoolError:
            declared_unset = False
        if not declared_unset:
            raise
        value, text = None, "Parameter not set."
    return value, _get_text(value, text, hide_type)


@param.command("get")
@click.argument("name")
@click.argument("param_name", required=False, metavar="[PARAM]")
@click.option("--hide-type", is_flag=True, help="ROS 2: print only the value, not its type.")
@ros2_param_options
@json_option
@click.pass_context
def get(
    ctx: click.Context, name: str, param_name: str | None, hide_type: bool, include_hidden: bool,
    node_timeout: float, as_json: bool,
) -> None:  # fmt: skip
    """Print a parameter (a namespace prints as a YAML mapping). ROS 2: NODE then PARAM, or PARAM alone
    for its value on every node.

    \b
    Examples:
      rostool param get /rosdistro
      rostool --ros2 param get /talker use_sim_time --hide-type
      rostool --ros2 param get use_sim_time          # every node that has it
    """
    with live_graph(ctx) as graph:
        _ros2_only(graph, hide_type=hide_type, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            _ros2_only_args(graph, param_name, "rostool param get NODE PARAM")
            value, text = graph.parameters(None).show(name)
            click.echo(to_json(value) if as_json else text, nl=not as_json)
            return
        if param_name is None and name.startswith("/"):  # a node's name: no parameter name starts so
            raise RostoolError("ROS 2 parameters belong to a node: rostool param get NODE PARAM")
        if param_name is None:
            _get_every_node(graph, name, hide_type, include_hidden, as_json)
            return
        node = _find_node(graph, name, include_hidden, node_timeout)
        value, text = _show_ros2(graph, node, param_name, hide_type)
    click.echo(to_json(value) if as_json else text, nl=not as_json)


def to_json(value: Any) -> str:
    from rostool.output.json_text import dumps

    return dumps(value) + "\n"


def _get_every_node(graph: Any, name: str, hide_type: bool, include_hidden: bool, as_json: bool) -> None:
    """`param get PARAM`: the value on every node that has it, under the node's name."""
    found: dict[str, tuple[Any, str]] = {}
    for node in _ros2_nodes(graph, include_hidden):
        try:
            found[node] = _show_ros2(graph, node, name, hide_type)
        except RostoolError:
            continue  # the node has no such parameter, or no parameter services
    if as_json:
        print_json({node: value for node, (value, _) in found.items()})
    elif not found:
        click.echo(f"Parameter '{name}' not set on any node")
    for node, (_, text) in found.items() if not as_json else ():
        click.echo(f"{node}:\n  {text}")


@param.command("set", context_settings={"ignore_unknown_options": True})
@click.argument("name")
@click.argument("value")
@click.argument("more", nargs=-1, metavar="[VALUE2] [PARAM VALUE]...")
@click.option("-t", "--textfile", is_flag=True, help="VALUE is a file whose text becomes a string parameter.")
@ros2_param_options
@click.pass_context
def set_(
    ctx: click.Context, name: str, value: str, more: tuple[str, ...], textfile: bool, include_hidden: bool,
    node_timeout: float,
) -> None:  # fmt: skip
    """Set a parameter; VALUE is YAML, so 0.05 is a float, 5 an int, true a bool, [1, 2] a list.

    ROS 2: NODE, then PARAM VALUE pairs (several pairs print one line each, prefixed by the name).

    \b
    Examples:
      rostool param set /wheel_radius 0.05
      rostool param set /robot "{name: r2, wheels: 4}"
      rostool param set /label "'42'"        # the string "42"
      rostool --ros2 param set /talker use_sim_time true
      rostool --ros2 param set /talker rate 5 label r2
    """
    from rostool.interfaces.values import parse_yaml

    with live_graph(ctx) as graph:
        _ros2_only(graph, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            _ros2_only_args(graph, more[0] if more else None, "rostool param set NODE PARAM VALUE")
            parsed = _read_text(value) if textfile else parse_yaml(value, f"the value of {name}")
            params = graph.parameters(None)
            ok, reason = params.set(name, parsed)
            if not ok:
                raise RostoolError(f"setting parameter {name} on {params.node} failed: {reason or 'refused'}")
            return
        pairs = (value, *more)
        if not more or len(pairs) % 2:
            raise RostoolError("ROS 2 parameters belong to a node: give NODE, then name/value pairs")
        node = _find_node(graph, name, include_hidden, node_timeout)
        params = graph.parameters(node)
        failed = 0
        for param_name, text in zip(pairs[::2], pairs[1::2], strict=True):
            parsed = _read_text(text) if textfile else parse_yaml(text, f"the value of {param_name}")
            ok, reason = params.set(param_name, parsed)
            outcome = "Set parameter successful" if ok else "Setting parameter failed"
            failed += not _report(ok, outcome, reason, param_name, params.node, several=len(pairs) > 2)
    if failed:
        ctx.exit(1)


@param.command("describe")
@click.argument("node")
@click.argument("names", nargs=-1, required=True, metavar="PARAM...")
@ros2_param_options
@json_option
@click.pass_context
def describe(
    ctx: click.Context, node: str, names: tuple[str, ...], include_hidden: bool, node_timeout: float,
    as_json: bool,
) -> None:  # fmt: skip
    """ROS 2: show a parameter's type, description and constraints.

    \b
    Example:
      rostool --ros2 param describe /talker use_sim_time
    """
    with live_graph(ctx) as graph:
        if graph.style != "ros2":
            raise RostoolError("param describe applies to ROS 2 parameters (rosparam has no descriptors)")
        params = graph.parameters(_find_node(graph, node, include_hidden, node_timeout))
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
@click.argument("param_names", nargs=-1, metavar="[PARAM]...")
@ros2_param_options
@click.pass_context
def delete(
    ctx: click.Context, name: str, param_names: tuple[str, ...], include_hidden: bool, node_timeout: float
) -> None:
    """Delete a parameter (or a whole namespace). ROS 2: NODE then PARAM (several: one line each).

    \b
    Examples:
      rostool param delete /wheel_radius
      rostool --ros2 param delete /talker my_param
    """
    with live_graph(ctx) as graph:
        _ros2_only(graph, include_hidden_nodes=include_hidden)
        if graph.style != "ros2":
            _ros2_only_args(graph, param_names[0] if param_names else None, "rostool param delete NODE PARAM")
            params = graph.parameters(None)
            ok, reason = params.delete(name)
            if not ok:
                raise RostoolError(
                    f"deleting parameter {name} on {params.node} failed: {reason or 'refused'}"
                )
            return
        if not param_names:
            raise RostoolError("ROS 2 parameters belong to a node: rostool param delete NODE PARAM")
        params = graph.parameters(_find_node(graph, name, include_hidden, node_timeout))
        failed = 0
        for param_name in param_names:
            ok, reason = params.delete(param_name)
            outcome = "Deleted parameter successfully" if ok else "Deleting parameter failed"
            failed += not _report(ok, outcome, reason, param_name, params.node, several=len(param_names) > 1)
    if failed:
        ctx.exit(1)


@param.command("dump")
@click.argument("file", metavar="FILE|NODE")
@click.argument("namespace", required=False, metavar="[NAMESPACE|FILE]")
@click.option(
    "--output-dir",
    type=click.Path(),
    metavar="DIR",
    help="ROS 2: write DIR/<node>.yaml (ns/node -> ns__node.yaml) instead of printing; DIR must exist, as "
    "in ros2 param dump.",
)
@click.option(
    "--print", "print_only", is_flag=True, help="ROS 2: print (the default; wins over --output-dir)."
)
@click.option("-a", "--all", "all_nodes", is_flag=True, hidden=True)
@click.option("--service-timeout", type=click.FloatRange(min=0), hidden=True)
@ros2_param_options
@json_option
@click.pass_context
def dump(
    ctx: click.Context, file: str, namespace: str | None, output_dir: str | None, print_only: bool,
    all_nodes: bool, service_timeout: float | None, include_hidden: bool, node_timeout: float, as_json: bool,
) -> None:  # fmt: skip
    """Write parameters (all, or under NAMESPACE) to a YAML FILE ("-" for stdout).

    ROS 2: every parameter of NODE, printed (or written to FILE, or to --output-dir) in the parameter file
    layout that `param load` and a node's --params-file read.

    \b
    Examples:
      rostool param dump params.yaml
      rostool param dump robot.yaml /robot
      rostool --ros2 param dump /talker > talker.yaml
      mkdir -p params && rostool --ros2 param dump /robot/talker --output-dir params/
    """
    from rostool.output.yaml_text import param_yaml

    with live_graph(ctx) as graph:
        ros2 = graph.style == "ros2"
        _ros2_only(
            graph, output_dir=output_dir, print=print_only, include_hidden_nodes=include_hidden or all_nodes
        )
        if ros2:
            if output_dir and not print_only and not Path(output_dir).is_dir():
                raise RostoolError(f"'{output_dir}' is not a valid directory.")
            node = _find_node(graph, file, include_hidden or all_nodes, node_timeout)
            target = namespace or "-"
            if output_dir and not print_only:
                target = str(Path(output_dir) / (node.lstrip("/").replace("/", "__") + ".yaml"))
        else:
            node, target = namespace, file
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
@click.option("--use-wildcard", is_flag=True, hidden=True)  # newer ros2cli's spelling of the default
@ros2_param_options
@click.pass_context
def load(
    ctx: click.Context, file: str, namespace: str | None, no_use_wildcard: bool, use_wildcard: bool,
    include_hidden: bool, node_timeout: float,
) -> None:  # fmt: skip
    """Set parameters from a YAML FILE ("-" for stdin), under NAMESPACE.

    ROS 2: NODE then FILE, a parameter file as `param dump` writes it; the node's own section and the
    '/**' section for every node are loaded, the node's own winning.

    \b
    Examples:
      rostool param load params.yaml /robot
      rostool --ros2 param load /talker talker.yaml
      rostool --ros2 param load /talker common.yaml --no-use-wildcard
    """
    if use_wildcard and no_use_wildcard:
        raise RostoolError("give --use-wildcard or --no-use-wildcard, not both")
    with live_graph(ctx) as graph:
        node = namespace or "/"
        _ros2_only(graph, no_use_wildcard=no_use_wildcard, use_wildcard=use_wildcard,
                   include_hidden_nodes=include_hidden)  # fmt: skip
        if graph.style == "ros2":
            if namespace is None:
                raise RostoolError("ROS 2 parameters belong to a node: rostool param load NODE FILE")
            node, file = _find_node(graph, file, include_hidden, node_timeout), namespace
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


def _report(ok: bool, outcome: str, reason: str, name: str, node: str, several: bool) -> bool:
    """ros2 param set/delete's line for one parameter (prefixed by its name when several are given); a
    single parameter's failure is the command's one error line."""
    line = outcome + (f": {reason}" if reason else "")
    if not several and not ok:
        raise RostoolError(f"{line} (parameter {name} of {node})")
    click.echo(f"{name}: {line}" if several else line, err=not ok)
    return ok
