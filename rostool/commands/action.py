"""`rostool action`: list, info, show, send-goal, cancel (actionlib over topics, ROS 1); on ROS 2 list, info
and send-goal in ros2 action's forms and output, and cancel over ACTION/_action/cancel_goal."""

from __future__ import annotations

import re
import sys
import threading
from typing import Any

import click

from rostool.commands._common import ignored_ros2_options, json_option, live_graph, print_json
from rostool.commands.srv import interfaces_option
from rostool.errors import RostoolError

_TYPE_NAME = re.compile(r"[A-Za-z][\w]*/(action/)?[A-Za-z]\w*\Z")


@click.group()
def action() -> None:
    """Use actionlib actions (ROS 1) and ROS 2 actions: list servers, send goals and follow them, cancel.

    Goal, result and feedback types come from .action files in source trees (--interfaces,
    ROS_PACKAGE_PATH, the current workspace; on ROS 2 also AMENT_PREFIX_PATH) or the built-in types: no
    catkin or colcon build needed.

    \b
    Examples:
      rostool action list
      rostool action info /navigate_2d_action
      rostool action send-goal /navigate_2d_action "{point: {x: 1.0, y: 2.0}}" --feedback
      rostool action cancel /navigate_2d_action
      rostool --ros2 action send-goal /fibonacci example_interfaces/action/Fibonacci "{order: 5}" --feedback
      rostool --ros2 action cancel /fibonacci
      rostool --ros2 action send_goal -f /fibonacci test_msgs/action/Fibonacci "{order: 5}"

    Flags and output follow the selected ROS version: actionlib's tools' under ROS 1, ros2 action's under
    ROS 2 (send_goal is send-goal). --json works in both. ros2cli flags with no meaning here (--spin-time,
    -s/--use-sim-time) are accepted and ignored.
    """


count_option = click.option(
    "-c", "--count-actions", "--count", "count", is_flag=True, help="Only the number of actions."
)


def _ros2_flags(graph: Any, verb: str, **given: bool) -> None:
    used = [name for name, value in given.items() if value]
    if used and graph.style != "ros2":
        flags = ", ".join("--" + name.replace("_", "-") for name in used)
        raise RostoolError(f"action {verb} {flags}: ros2 action forms; under ROS 1 see `rostool action info`")


@action.command("list")
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: also print each action's type.")
@count_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def list_actions(ctx: click.Context, show_types: bool, count: bool, as_json: bool) -> None:
    """List the actions of the live graph (namespaces with goal, cancel, status, feedback, result; on ROS 2
    actions with a server).

    \b
    Examples:
      rostool action list
      rostool --ros2 action list -t          # /fibonacci [example_interfaces/action/Fibonacci]
    """
    with live_graph(ctx) as graph:
        _ros2_flags(graph, "list", show_types=show_types)
        found = graph.actions()
    if count:
        click.echo(str(len(found)))
        return
    if as_json:
        print_json([vars(a) for a in found])
        return
    for summary in found:
        click.echo(f"{summary.name} [{summary.type}]" if show_types else summary.name)


@action.command("info")
@click.argument("name", metavar="ACTION")
@click.option("--wait", "wait", type=click.FloatRange(min=0), default=2.0, show_default=True,
              help="Seconds to wait for the server's goal status list.")  # fmt: skip
@click.option("-t", "--show-types", is_flag=True, help="ROS 2: each client and server with the type.")
@click.option("-c", "--count", is_flag=True, help="ROS 2: only the numbers of clients and servers.")
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def info(ctx: click.Context, name: str, wait: float, show_types: bool, count: bool, as_json: bool) -> None:
    """Show an action's type, server, clients and the goals its server tracks (ROS 2: its clients and
    servers, as ros2 action info does; for an action nobody serves, 0 of each and then the error).

    \b
    Examples:
      rostool action info /navigate_2d_action
      rostool --ros2 action info -t /fibonacci
    """
    with live_graph(ctx) as graph:
        _ros2_flags(graph, "info", show_types=show_types, count=count)
        style = graph.style
        if style == "ros2" and graph.resolve(name) not in {a.name for a in graph.actions()}:
            found = {"name": graph.resolve(name), "type": None, "clients": [], "servers": []}
        else:
            found = graph.action_info(name, wait)
    if as_json:
        print_json(found)
    elif style == "ros1":
        _info_ros1(found, wait)
    else:
        click.echo(f"Action: {name}")
        for title, nodes in (("Action clients", found["clients"]), ("Action servers", found["servers"])):
            click.echo(f"{title}: {len(nodes)}")
            for node in [] if count else nodes:
                click.echo(f"    {node} [{found['type']}]" if show_types else f"    {node}")
        if not found["servers"] and not found["clients"]:  # ros2 exits 0 here; an unknown name is an error
            raise RostoolError(
                f"unknown action {found['name']}: no server announces it (`rostool action list`)"
            )


@action.command("type")
@click.argument("name", metavar="ACTION")
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def type_(ctx: click.Context, name: str) -> None:
    """Print an action's type (ros2 action type; nothing and exit 1 when no server announces it).

    \b
    Examples:
      rostool --ros2 action type /fibonacci       # test_msgs/action/Fibonacci
      rostool action type /navigate_2d_action
    """
    with live_graph(ctx) as graph:
        resolved = graph.resolve(name)
        types = sorted({a.type for a in graph.actions() if a.name == resolved and a.type})
    if not types:  # as ros2 action type: nothing on stdout, exit 1
        raise RostoolError(f"unknown action {resolved}: no server announces it (`rostool action list`)")
    click.echo("\n".join(types))


@action.command("find")
@click.argument("type_name", metavar="TYPE")
@count_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def find(ctx: click.Context, type_name: str, count: bool) -> None:
    """List the actions of type TYPE (ros2 action find).

    \b
    Examples:
      rostool --ros2 action find test_msgs/action/Fibonacci
      rostool --ros2 action find -c test_msgs/action/Fibonacci
    """
    from rostool.interfaces.names import to_store_name

    with live_graph(ctx) as graph:
        wanted = {type_name, to_store_name(type_name, "action")}
        names = sorted(a.name for a in graph.actions() if a.type in wanted)
    click.echo(str(len(names)) if count else "\n".join(names), nl=count or bool(names))


def _info_ros1(found: dict[str, Any], wait: float) -> None:
    click.echo(f"Action: {found['name']}\nType: {found['type'] or '?'}")
    for title, nodes in (("Server", found["servers"]), ("Clients", found["clients"])):
        click.echo(f"{title}: {'None' if not nodes else ''}")
        for node in nodes:
            click.echo(f" * {node}")
    goals = found["goals"]
    if goals is None:
        click.echo(f"Goals: unknown (no status from the server within {wait:g} s)")
        return
    click.echo(f"Goals: {'None' if not goals else ''}")
    for goal in goals:
        click.echo(f" * {goal['id']}: {goal['status']}" + (f" ({goal['text']})" if goal["text"] else ""))


@action.command("show")
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
    from rostool.commands._common import interface_style
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


def _split_goal_args(values: tuple[str, ...]) -> tuple[str | None, tuple[str, ...]]:
    """[TYPE] GOAL...: a first value spelled pkg/Type (never valid goal YAML) is the type."""
    if len(values) >= 2 and _TYPE_NAME.match(values[0]):
        return values[0], values[1:]
    return None, values


@action.command("send-goal", context_settings={"ignore_unknown_options": True})
@click.argument("name", metavar="ACTION")
@click.argument("values", nargs=-1, metavar="[TYPE] GOAL...")
@click.option(
    "-f", "--feedback", "show_feedback", is_flag=True, help="Print each feedback message as it arrives."
)
@click.option("--stdin", "from_stdin", is_flag=True, help="Read the goal (YAML) from standard input.")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    help="Cancel the goal and exit 1 when it has no result after S seconds.",
)
@interfaces_option
@json_option
@ignored_ros2_options("no_daemon", "spin_time", "use_sim_time")
@click.pass_context
def send_goal(
    ctx: click.Context,
    name: str,
    values: tuple[str, ...],
    show_feedback: bool,
    from_stdin: bool,
    timeout: float | None,
    interface_paths: tuple[str, ...],
    as_json: bool,
) -> None:
    """Send a goal and wait for its result; Ctrl+C (or --timeout) cancels the goal first.

    GOAL is one YAML mapping, or the goal's field values in order. TYPE (pkg/Type) may be left out when
    the server is running: it is read from ACTION/goal. Exit status: 0 when the goal SUCCEEDED, 1 for any
    other final status or a timeout, 130 on Ctrl+C.

    \b
    Examples:
      rostool action send-goal /navigate_2d_action "{point: {x: 1.0, y: 2.0, z: 0.0}}" --feedback
      rostool action send-goal /fibonacci actionlib_tutorials/Fibonacci "{order: 5}" --timeout 30
      rostool --ros2 action send-goal /count robo_msgs/action/Count "{count: 3}" --interfaces ~/ros2_ws
    """
    from rostool.interfaces.values import message_args

    if from_stdin:
        values = (*values, sys.stdin.read())
    if not values:
        raise click.UsageError("Missing argument '[TYPE] GOAL...' (or give the goal on stdin with --stdin).")
    type_name, goal_values = _split_goal_args(values)
    goal = message_args(goal_values)
    with live_graph(ctx, interface_paths) as graph:
        watcher = (_Renderer if graph.style == "ros1" else _Ros2Renderer)(as_json, show_feedback)
        outcome = graph.send_goal(name, type_name, goal, timeout, watcher)
    if not outcome.succeeded:
        ctx.exit(1)


class _Renderer:
    """Prints goal events: YAML blocks for people, one JSON object per event for scripts."""

    def __init__(self, as_json: bool, show_feedback: bool) -> None:
        self.as_json = as_json
        self.show_feedback = show_feedback

    def waiting(self, text: str) -> None:
        click.echo(text, err=True)

    def canceling(self, goal_id: str) -> None:
        pass  # actionlib's canceling shows in the status events

    def sent(self, goal_id: str, goal: Any = None, accepted: bool = True) -> None:
        if self.as_json:
            print_json({"event": "sent", "goal_id": goal_id})
        else:
            click.echo(f"Goal sent: {goal_id}")
        sys.stdout.flush()

    def event(self, event: Any) -> None:
        from rostool.output.plain import to_plain

        if event.kind == "feedback" and not self.show_feedback:
            return
        if self.as_json:
            body: dict[str, Any] = {"event": event.kind, "status": event.status_name}
            if event.text:
                body["text"] = event.text
            if event.message is not None:
                body[event.kind] = to_plain(event.message)
            print_json(body)
        elif event.kind == "feedback":
            click.echo("Feedback:\n" + _indented(event.message))
        else:
            text = f" ({event.text})" if event.text else ""
            click.echo(f"Status: {event.status_name}{text}")
            if event.message is not None:
                click.echo("Result:\n" + _indented(event.message))
        sys.stdout.flush()


class _Ros2Renderer(_Renderer):
    """ros2 action send_goal's text, or one JSON object per event."""

    def __init__(self, as_json: bool, show_feedback: bool) -> None:
        super().__init__(as_json, show_feedback)
        # a feedback can overtake the server's answer to the goal; ros2 prints the answer first
        self.accepted = False
        self.early: list[Any] = []
        self._lock = threading.RLock()

    def sent(self, goal_id: str, goal: Any = None, accepted: bool = True) -> None:
        with self._lock:
            self._sent(goal_id, goal, accepted)

    def _sent(self, goal_id: str, goal: Any, accepted: bool) -> None:
        from rostool.output.plain import to_plain
        from rostool.output.yaml_text import to_yaml

        if not self.waited:  # ros2 prints it even when the server is there at once
            self.waiting("Waiting for an action server to become available...")
        if self.as_json:
            goal_plain = to_plain(goal, "ros2")
            print_json({"event": "sent", "goal_id": goal_id, "accepted": accepted, "goal": goal_plain})
        else:
            answer = f"Goal accepted with ID: {goal_id}\n" if accepted else "Goal was rejected."
            click.echo(f"Sending goal:\n     {to_yaml(goal, 'ros2')}\n\n{answer}")
        sys.stdout.flush()
        self.accepted = True
        for early in self.early:
            self._event(early)
        self.early.clear()

    waited = False

    def waiting(self, text: str) -> None:
        self.waited = True
        click.echo(text, err=self.as_json)  # ros2 action send_goal prints it first, on stdout
        sys.stdout.flush()

    def canceling(self, goal_id: str) -> None:
        if self.as_json:
            print_json({"event": "canceling", "goal_id": goal_id})
        else:
            click.echo("Canceling goal...")
        sys.stdout.flush()

    def event(self, event: Any) -> None:
        with self._lock:
            self._event(event)

    def _event(self, event: Any) -> None:
        from rostool.output.plain import to_plain
        from rostool.output.yaml_text import to_yaml

        if event.kind == "feedback" and not self.show_feedback:
            return
        if not self.accepted:
            self.early.append(event)
            return
        if self.as_json:
            body: dict[str, Any] = {"event": event.kind}
            if event.kind == "result":
                body["status"] = event.status_name
            body[event.kind] = to_plain(event.message, "ros2")
            print_json(body)
        elif event.kind == "feedback":
            click.echo(f"Feedback:\n    {to_yaml(event.message, 'ros2')}\n")
        else:
            click.echo(f"Result:\n    {to_yaml(event.message, 'ros2')}\n")
            click.echo(f"Goal finished with status: {event.status_name}")
        sys.stdout.flush()


def _indented(message: Any) -> str:
    from rostool.output.yaml_text import to_yaml

    text = to_yaml(message)
    return "\n".join("  " + line for line in text.splitlines()) if text else "  {}"


@action.command("cancel")
@click.argument("name", metavar="ACTION")
@click.argument("goal_id", required=False)
@click.option("--all", "cancel_all", is_flag=True, help="Cancel every goal (the default without GOAL_ID).")
@json_option
@click.pass_context
def cancel(ctx: click.Context, name: str, goal_id: str | None, cancel_all: bool, as_json: bool) -> None:
    """Ask an action server to cancel one goal (by its id), or every goal when no GOAL_ID is given.

    On ROS 2 GOAL_ID is the id send-goal printed (32 hex digits) and the goals the server is canceling are
    printed; a server that refuses (or does not know the goal) makes the exit status 1.

    \b
    Examples:
      rostool action cancel /navigate_2d_action
      rostool action cancel /navigate_2d_action /rostool-4242-1-1712345678.5
      rostool --ros2 action cancel /fibonacci 5f1b4c0e2d0a4b8e9c3f6a7d8e9f0a1b
    """
    from rostool.output.plain import to_plain

    if cancel_all and goal_id is not None:
        raise RostoolError("give a GOAL_ID or --all, not both (`rostool action info ACTION` lists goal ids)")
    with live_graph(ctx) as graph:
        canceling = graph.cancel_goals(name, goal_id)
        style, action = graph.style, graph.resolve(name)
    if style == "ros1":
        if as_json:
            print_json({"action": name, "goal_id": goal_id})
        else:
            click.echo(f"canceled {goal_id or 'every goal'} of {name}")
    elif as_json:
        goals = [{"goal_id": g.goal_id, "stamp": to_plain(g.stamp, "ros2")} for g in canceling]
        print_json({"action": action, "goals_canceling": goals})
    else:
        count = f"Canceling {len(canceling)} goal(s) of" if canceling else "No goals of"
        click.echo(f"{count} {action}" + (":" if canceling else " to cancel"))
        for goal in canceling:
            click.echo(f"    {goal.goal_id}")


action.add_command(send_goal, "send_goal")  # ros2 action's spelling
