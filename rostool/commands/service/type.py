"""`rostool service type`: a service's type (rosservice type asks the service, ros2 service type the
graph)."""

from __future__ import annotations

from rostool.commands._common import announced_type_verb

type_ = announced_type_verb(
    "service",
    """Print the type of a service (asked from the service itself).

    \b
    Examples:
      rostool service type /sum_two_ints      # sum_two_numbers/SumTwoInts
      rostool --ros2 service type /add_two_ints   # example_interfaces/srv/AddTwoInts
    """,
    announced=lambda graph: [(name, type_name) for name, type_name, _nodes in graph.services()],
    ros1_type=lambda graph, name: graph.service_type(name),
)
