"""ROS 2 service types: rosbags' type stores hold messages only, so the services rostool itself needs are
defined here from their .srv text (parameter, lifecycle, logger and type-description services, a few
examples); others come from .srv files in the interface sources (definitions.py)."""

from __future__ import annotations

from rostool.errors import RostoolError
from rostool.interfaces.definitions import service_types
from rostool.interfaces.ros2_types import Ros2Types
from rostool.interfaces.rosbag2_srv import ROSBAG2_SERVICES

# services rosbags' type stores lack (they hold the messages): their .srv text
SRV_DEFINITIONS: dict[str, str] = {
    "rcl_interfaces/srv/ListParameters": "uint64 DEPTH_RECURSIVE=0\nstring[] prefixes\nuint64 depth\n"
    "---\nListParametersResult result\n",
    "rcl_interfaces/srv/GetParameters": "string[] names\n---\nParameterValue[] values\n",
    "rcl_interfaces/srv/SetParameters": "Parameter[] parameters\n---\nSetParametersResult[] results\n",
    "rcl_interfaces/srv/DescribeParameters": "string[] names\n---\nParameterDescriptor[] descriptors\n",
    "rcl_interfaces/srv/GetParameterTypes": "string[] names\n---\nuint8[] types\n",
    "action_msgs/srv/CancelGoal": "GoalInfo goal_info\n---\nint8 ERROR_NONE=0\nint8 ERROR_REJECTED=1\n"
    "int8 ERROR_UNKNOWN_GOAL_ID=2\nint8 ERROR_GOAL_TERMINATED=3\n"
    "int8 return_code\nGoalInfo[] goals_canceling\n",
    "example_interfaces/srv/AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
    "example_interfaces/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "example_interfaces/srv/Trigger": "---\nbool success\nstring message\n",
    "lifecycle_msgs/srv/GetState": "---\nState current_state\n",
    "lifecycle_msgs/srv/ChangeState": "Transition transition\n---\nbool success\n",
    "lifecycle_msgs/srv/GetAvailableTransitions": "---\nTransitionDescription[] available_transitions\n",
    "rcl_interfaces/srv/GetLoggerLevels": "string[] names\n---\nLoggerLevel[] levels\n",
    "rcl_interfaces/srv/SetLoggerLevels": "LoggerLevel[] levels\n---\nSetLoggerLevelsResult[] results\n",
    "std_srvs/srv/Empty": "---\n",
    "std_srvs/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "std_srvs/srv/Trigger": "---\nbool success\nstring message\n",
    # REP 2016, served by every node from Iron on (see type_description.py)
    "type_description_interfaces/srv/GetTypeDescription": "string type_name\nstring type_hash\n"
    "bool include_type_sources true\n---\nbool successful\nstring failure_reason\n"
    "TypeDescription type_description\nTypeSource[] type_sources\nKeyValue[] extra_information\n",
    **ROSBAG2_SERVICES,  # the player's and recorder's services (bag play, bag record --snapshot-mode)
}


def register_service(types: Ros2Types, srv_type: str, text: str | None = None) -> tuple[str, str]:
    """Make `pkg/srv/Name_Request` and `_Response` known to the session's store; returns both names.

    Looked up in order: the store, `text`, rostool's built-in definitions, then .srv source files."""
    parts = srv_type.strip().strip("/").split("/")
    if len(parts) == 2:
        pkg, name = parts
        kind = "srv"
    elif len(parts) == 3 and parts[1] in ("srv", "action"):  # actions' services are `pkg/action/X_SendGoal`
        pkg, kind, name = parts
    else:
        raise RostoolError(f"bad service type {srv_type!r}: use pkg/srv/Name (or pkg/Name)")
    full = f"{pkg}/{kind}/{name}"
    request, response = f"{full}_Request", f"{full}_Response"
    if types.in_store(request) and types.in_store(response):
        return request, response
    text = text if text is not None else SRV_DEFINITIONS.get(full)
    if text is None:
        if types.knows(request) and types.knows(response):
            return request, response
        raise types.unknown("service", full, sorted(SRV_DEFINITIONS))
    types.register(service_types(full, text, f"the definition of {full}"))
    return request, response
