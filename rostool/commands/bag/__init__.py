"""`rostool bag`: info, echo, convert, filter, reindex, play, burst, record, export, plot, graph over .bag,
rosbag2 directories, .mcap and .db3; each verb in its own module, imported only when used.

Under ROS 2 (--ros2, ROS_VERSION=2) `record` and `play` take ros2 bag's flags (`record_ros2`, `play_ros2`):
both forms of a verb parse into one request and run the same code.
"""

from __future__ import annotations

import click

from rostool.commands._common import ExtensibleGroup

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
_VERBS = {
    "info": "info:info", "echo": "echo:echo", "convert": "convert:convert", "filter": "filter:filter_",
    "reindex": "reindex:reindex", "play": "play:play", "record": "record:record", "export": "export:export",
    "plot": "plot:plot", "graph": "graph:graph", "burst": "burst:burst",
}  # fmt: skip
_ROS2_FORMS = {"record": "record_ros2:record", "play": "play_ros2:play"}


@click.group(
    cls=ExtensibleGroup,
    context_settings=CONTEXT,
    extra={verb: f"{__name__}.{spec}" for verb, spec in _VERBS.items()},
    ros2_forms={verb: f"{__name__}.{spec}" for verb, spec in _ROS2_FORMS.items()},
)
def bag() -> None:
    """Inspect, convert and repair bags: ROS 1 .bag, rosbag2 directories, .mcap and .db3 files.

    \b
    Examples:
      rostool bag info run.bag
      rostool bag echo run.bag /odom -n 3
      rostool bag convert run.bag run.mcap
      rostool bag filter run.bag out.bag --filter 'm.linear.x > 0'
    """
