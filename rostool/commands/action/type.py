"""`rostool action type`: an action's type (ros2 action type)."""

from __future__ import annotations

from rostool.commands._common import announced_type_verb

type_ = announced_type_verb(
    "action",
    """Print an action's type (ros2 action type; nothing and exit 1 when no server announces it).

    \b
    Examples:
      rostool --ros2 action type /fibonacci       # test_msgs/action/Fibonacci
      rostool action type /navigate_2d_action
    """,
    announced=lambda graph: [(summary.name, summary.type) for summary in graph.actions()],
)
