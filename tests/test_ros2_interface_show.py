"""`rostool msg|srv|action show`, `msg list`, `msg md5` for ROS 2 types, as `ros2 interface show` and
`ros2 interface list` print them: rosbags' distro store, rostool's built-in service and action definitions,
and .msg/.srv/.action source files. No graph: nothing here touches a network."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from rosbags.typesys import Stores, get_typestore

from tests.support import interface_workspace, rostool
from tests.test_ros2_graph import ros2_env
from tests.test_ros2_interfaces import SOURCES

POSE_STAMPED = """std_msgs/Header header
\tbuiltin_interfaces/Time stamp
\t\tint32 sec
\t\tuint32 nanosec
\tstring frame_id
Pose pose
\tPoint position
\t\tfloat64 x
\t\tfloat64 y
\t\tfloat64 z
\tQuaternion orientation
\t\tfloat64 x
\t\tfloat64 y
\t\tfloat64 z
\t\tfloat64 w
"""


@pytest.fixture
def workspace(tmp_path: Path) -> Path:
    return interface_workspace(tmp_path / "ws", SOURCES)


def test_msg_show_expands_nested_types_with_tabs() -> None:
    for args in (
        ["--ros2", "msg", "show", "geometry_msgs/PoseStamped"],
        ["msg", "show", "geometry_msgs/msg/PoseStamped"],
    ):
        done = rostool(args, ros2_env())
        assert done.returncode == 0 and done.stdout == POSE_STAMPED, (args, done.stderr)
    # A ROS 2 name is enough, whatever ROS_VERSION says is unset.
    no_version = {k: v for k, v in ros2_env().items() if k != "ROS_VERSION"}
    assert rostool(["msg", "show", "geometry_msgs/msg/PoseStamped"], no_version).stdout == POSE_STAMPED


def test_msg_show_prints_constants_like_rosidl() -> None:
    shown = rostool(["--ros2", "msg", "show", "sensor_msgs/msg/NavSatFix"], ros2_env()).stdout.splitlines()
    at = shown.index("NavSatStatus status")
    assert shown[at + 1 : at + 3] == ["\tint8 STATUS_UNKNOWN=-2", "\tint8 STATUS_NO_FIX=-1"]
    assert "\tuint16 service" in shown and "float64[9] position_covariance" in shown
    assert "uint8 COVARIANCE_TYPE_UNKNOWN=0" in shown


def test_srv_and_action_show() -> None:
    env = ros2_env()
    add = rostool(["--ros2", "srv", "show", "example_interfaces/srv/AddTwoInts"], env)
    assert add.stdout == "int64 a\nint64 b\n---\nint64 sum\n", add.stderr
    fib = rostool(["--ros2", "action", "show", "example_interfaces/action/Fibonacci"], env)
    assert fib.stdout == "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n", fib.stderr
    # `ros2 interface show` takes every kind; so does msg show.
    assert rostool(["msg", "show", "example_interfaces/srv/AddTwoInts"], env).stdout == add.stdout
    params = rostool(["srv", "show", "rcl_interfaces/srv/SetParameters"], env).stdout.splitlines()
    assert params[:4] == [
        "Parameter[] parameters",
        "\tstring name",
        "\tParameterValue value",
        "\t\tuint8 type",
    ]
    assert params[-4:] == ["---", "SetParametersResult[] results", "\tbool successful", "\tstring reason"]


def test_custom_types_from_a_workspace(workspace: Path) -> None:
    env = ros2_env()
    rate = rostool(["--ros2", "srv", "show", "robo_msgs/srv/Rate", "--interfaces", str(workspace)], env)
    assert rate.stdout == (
        'Status status\n\tint32 LEVEL_MAX=9\n\tstring name "un#named"\n\tPart[] parts\n\t\tstring label\n'
        "\t\tfloat64 weight 0.5\n\tgeometry_msgs/Point where\n\t\tfloat64 x\n\t\tfloat64 y\n\t\tfloat64 z\n"
        "int64 factor\n---\nint64 score\nstring summary\n"
    ), rate.stderr
    count = rostool(
        ["action", "show", "robo_msgs/action/Count"], {**env, "ROSTOOL_INTERFACES": str(workspace)}
    )
    assert count.stdout == (
        "int32 count 2\nstring label\n---\nint32[] done\n---\nint32 step\nPart part\n\tstring label\n"
        "\tfloat64 weight 0.5\n"
    ), count.stderr
    raw = rostool(["action", "show", "robo_msgs/action/Count", "--raw", "--interfaces", str(workspace)], env)
    assert raw.stdout == SOURCES["robo_msgs/action/Count.action"]


def test_list_in_ros2_interface_list_form(workspace: Path) -> None:
    env = {**ros2_env(), "ROSTOOL_INTERFACES": str(workspace)}
    lines = rostool(["msg", "list"], env).stdout.splitlines()
    titles = [line for line in lines if not line.startswith("    ")]
    assert titles == ["Messages:", "Services:", "Actions:"]
    messages = lines[1 : lines.index("Services:")]
    assert "    std_msgs/msg/String" in messages and "    robo_msgs/msg/Part" in messages
    assert messages == sorted(messages)
    assert lines[lines.index("Actions:") + 1 :] == [
        "    example_interfaces/action/Fibonacci", "    robo_msgs/action/Count",
        "    test_msgs/action/Fibonacci",
    ]  # fmt: skip
    only_srvs = rostool(["srv", "list"], env).stdout.splitlines()
    assert only_srvs == rostool(["msg", "list", "-s"], env).stdout.splitlines()
    assert only_srvs[0] == "Services:" and "    robo_msgs/srv/Rate" in only_srvs
    as_json = json.loads(rostool(["msg", "list", "-m", "-a", "--json"], env).stdout)
    assert set(as_json) == {"messages", "actions"} and "geometry_msgs/msg/Twist" in as_json["messages"]
    ros1 = rostool(["--ros1", "msg", "list", "-m"], env)
    assert ros1.returncode == 1 and "apply to ROS 2 only" in ros1.stderr


def test_md5_is_the_rihs01_hash(workspace: Path) -> None:
    env = {**ros2_env(), "ROSTOOL_INTERFACES": str(workspace)}
    string = rostool(["msg", "md5", "std_msgs/msg/String"], env).stdout.strip()
    assert string == "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
    store = get_typestore(Stores.ROS2_JAZZY)
    for name in ("geometry_msgs/msg/PoseStamped", "sensor_msgs/msg/NavSatFix"):
        assert rostool(["--ros2", "msg", "md5", name], env).stdout.strip() == store.hash_rihs01(name)
    humble = get_typestore(Stores.ROS2_HUMBLE).hash_rihs01("rcl_interfaces/msg/ParameterDescriptor")
    ours = rostool(["msg", "md5", "rcl_interfaces/msg/ParameterDescriptor"], {**env, "ROS_DISTRO": "humble"})
    assert ours.stdout.strip() == humble
    custom = rostool(["msg", "md5", "robo_msgs/msg/Part"], env).stdout.strip()
    assert custom.startswith("RIHS01_") and len(custom) == 7 + 64


def test_unknown_type_is_one_line_naming_the_sources(tmp_path: Path) -> None:
    env = ros2_env()
    for verb, name in (
        ("msg", "nope_msgs/msg/Nothing"),
        ("srv", "nope_msgs/srv/Nothing"),
        ("action", "nope/Go"),
    ):
        done = rostool([verb, "show", name], env, cwd=tmp_path)
        assert done.returncode == 1 and done.stdout == "", done.stdout
        assert len(done.stderr.splitlines()) == 1, done.stderr
        assert "rosbags' built-in ROS 2 jazzy type store" in done.stderr, done.stderr
        assert "the interface sources (no --interfaces, ROS_PACKAGE_PATH or AMENT_PREFIX_PATH" in done.stderr
    srv_md5 = rostool(["--ros2", "srv", "md5", "std_srvs/srv/Trigger"], env)
    assert srv_md5.returncode == 1 and "no md5sum" in srv_md5.stderr


def test_ros1_answer_stays_the_default() -> None:
    env = {k: v for k, v in ros2_env().items() if k != "ROS_VERSION"}
    assert rostool(["msg", "show", "std_msgs/Header"], env).stdout == (
        "uint32 seq\ntime stamp\nstring frame_id\n\n"
    )
    assert (
        rostool(["msg", "md5", "std_msgs/String"], env).stdout.strip() == "992ce8a1687cec8c8bd883ec73ca41d1"
    )
