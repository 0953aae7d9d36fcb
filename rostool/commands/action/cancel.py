"""`rostool action cancel`: cancel one goal or every goal of an action."""

from __future__ import annotations

import click

from rostool.commands._common import json_option, live_graph, print_json
from rostool.errors import RostoolError


@click.command("cancel")
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
