"""The Graph protocol's parameters and actions on RclpyGraph; their modules (and the DDS backend's, whose
types, lines and parameter client they share) load on first use, so listing verbs start without them."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.graph.base import GoalWatcher, Parameters
    from rostool.graph.rclpy.graph import RclpyGraph


class ParameterVerbs:
    def parameters(self: RclpyGraph, node: str | None, timeout: float = 5.0) -> Parameters:
        from rostool.graph.rclpy.params import RclpyParameters

        if node is None:
            raise RostoolError("ROS 2 parameters belong to nodes: give the NODE first")
        return RclpyParameters(self, node, timeout)


class ActionVerbs:
    def actions(self: RclpyGraph) -> list[Any]:
        from rostool.graph.rclpy.actions import list_actions

        return list_actions(self)

    def action_info(self: RclpyGraph, name: str, wait: float) -> dict[str, Any]:
        action = self.resolve(name)
        found = next((a for a in self.actions() if a.name == action), None)
        if found is None:
            raise RostoolError(f"unknown action {action}: no server announces it (`rostool action list`)")
        return vars(found)

    def cancel_goals(self: RclpyGraph, name: str, goal_id: str | None) -> list[Any]:
        from rostool.graph.rclpy.actions import cancel_goals

        return cancel_goals(self, name, goal_id)  # type: ignore[return-value]

    def send_goal(
        self: RclpyGraph, name: str, kind: str | None, goal: Any, timeout: float | None, watcher: GoalWatcher
    ) -> Any:
        from rostool.graph.rclpy.actions import GoalRun

        return GoalRun(self, name, kind, goal, timeout, watcher).run()
