"""`rostool lifecycle`: nodes, get, list, set (ros2lifecycle's forms, output and exit statuses)."""

from __future__ import annotations

import sys
from typing import Any, NoReturn

import click
from click.shell_completion import CompletionItem

from rostool.commands._common import ignored_ros2_options, live_graph
from rostool.errors import RostoolError
from rostool.graph import lifecycle as lc

ros2cli_options = ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
hidden_nodes_option = click.option(
    "--include-hidden-nodes", "include_hidden", is_flag=True, help="Consider hidden nodes as well."
)


@click.group()
def lifecycle() -> None:
    """Get and change the states of ROS 2 lifecycle nodes (like ros2 lifecycle), through the
    lifecycle_msgs services every lifecycle node serves.

    \b
    Examples:
      rostool --ros2 lifecycle nodes
      rostool --ros2 lifecycle get /camera            # unconfigured [1]
      rostool --ros2 lifecycle list /camera           # the transitions available now
      rostool --ros2 lifecycle set /camera configure  # Transitioning successful

    --spin-time S waits S seconds for discovery when no graph daemon answers (as ros2cli);
    -s/--use-sim-time is accepted and ignored.
    """


def _fail(text: str) -> NoReturn:
    """ros2cli's way out of a verb: the text on stderr, exit 1."""
    click.echo(text, err=True)
    sys.exit(1)


def _find_node(graph: Any, name: str, include_hidden: bool) -> str:
    node = lc.absolute_node_name(name)
    if not lc.is_lifecycle_node(graph, node, include_hidden):
        _fail("Node not found")
    return node


def _service_failure(node: str, err: RostoolError) -> str:
    return f"Exception while calling service of node '{node}': {err}"


@lifecycle.command("nodes")
@click.option("-a", "--all", "include_hidden", is_flag=True, help="Display all nodes even hidden ones.")
@click.option("-c", "--count-nodes", "count", is_flag=True, help="Only the number of lifecycle nodes.")
@ros2cli_options
@click.pass_context
def nodes(ctx: click.Context, include_hidden: bool, count: bool) -> None:
    """List the lifecycle nodes of the graph.

    \b
    Examples:
      rostool --ros2 lifecycle nodes
      rostool --ros2 lifecycle nodes -a -c
    """
    with live_graph(ctx) as graph:
        found = lc.lifecycle_nodes(graph, include_hidden)
    if count:
        click.echo(str(len(found)))
    elif found:
        click.echo("\n".join(found))


@lifecycle.command("get")
@click.argument("node_name", metavar="NODE", required=False)
@hidden_nodes_option
@ros2cli_options
@click.pass_context
def get(ctx: click.Context, node_name: str | None, include_hidden: bool) -> None:
    """Print the lifecycle state of NODE, or `NODE: state [id]` for every lifecycle node.

    \b
    Examples:
      rostool --ros2 lifecycle get /camera     # unconfigured [1]
      rostool --ros2 lifecycle get             # /camera: unconfigured [1]
    """
    with live_graph(ctx) as graph:
        if node_name:
            queried = [_find_node(graph, node_name, include_hidden)]
        else:
            queried = lc.lifecycle_nodes(graph, include_hidden)
        states: dict[str, tuple[str, int]] = {}
        for node in queried:
            try:
                states[node] = lc.get_state(graph, node)
            except RostoolError as err:
                click.echo(_service_failure(node, err), err=True)
                if node_name:
                    sys.exit(1)
    for node, (label, state_id) in sorted(states.items()):
        click.echo(f"{'' if node_name else node + ': '}{label} [{state_id}]")


@lifecycle.command("list")
@click.argument("node_name", metavar="NODE")
@hidden_nodes_option
@click.option("-a", "--all", "every", is_flag=True, help="Display all existing transitions.")
@ros2cli_options
@click.pass_context
def list_transitions(ctx: click.Context, node_name: str, include_hidden: bool, every: bool) -> None:
    """Print the transitions NODE can take now (-a: its whole transition graph), with their ids.

    \b
    Examples:
      rostool --ros2 lifecycle list /camera       # - configure [1] ...
      rostool --ros2 lifecycle list /camera -a
    """
    with live_graph(ctx) as graph:
        node = _find_node(graph, node_name, include_hidden)
        try:
            found = lc.transitions(graph, node, every)
        except RostoolError as err:
            _fail(_service_failure(node_name, err))
    for t in found:
        click.echo(f"- {t.label} [{t.id}]\n\tStart: {t.start}\n\tGoal: {t.goal}")


def _complete_transition(
    _ctx: click.Context, _param: click.Parameter, incomplete: str
) -> list[CompletionItem]:
    """The transitions a user triggers (the others are the state machine's own)."""
    return [CompletionItem(label) for label in lc.USER_TRANSITIONS if label.startswith(incomplete)]


@lifecycle.command("set")
@click.argument("node_name", metavar="NODE")
@click.argument("transition", metavar="TRANSITION", shell_complete=_complete_transition)
@hidden_nodes_option
@ros2cli_options
@click.pass_context
def set_state(ctx: click.Context, node_name: str, transition: str, include_hidden: bool) -> None:
    """Trigger TRANSITION (a label or an id, as `lifecycle list` prints them) on NODE.

    \b
    Examples:
      rostool --ros2 lifecycle set /camera configure   # Transitioning successful
      rostool --ros2 lifecycle set /camera 3           # activate, by id
    """
    with live_graph(ctx) as graph:
        node = _find_node(graph, node_name, include_hidden)
        try:
            available = lc.transitions(graph, node)
        except RostoolError as err:
            _fail(_service_failure(node_name, err))
        chosen = next((t for t in available if t.label == transition), None) or next(
            (t for t in available if str(t.id) == transition), None
        )
        if chosen is None:
            listed = "".join(f"\n- {t.label} [{t.id}]" for t in available)
            _fail("Unknown transition requested, available ones are:" + listed)
        try:
            succeeded = lc.change_state(graph, node, chosen)
        except RostoolError as err:  # as ros2lifecycle: said on stderr, exit 0
            click.echo(_service_failure(node_name, err), err=True)
            return
    if succeeded:
        click.echo("Transitioning successful")
    else:
        click.echo("Transitioning failed", err=True)
