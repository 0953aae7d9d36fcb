"""Converting between ROS 1 and ROS 2 serializations (`bag/crossver.py`), read back by rosbags' own stores of
the other version: the bytes must carry the same values, and only the types a message uses are built (a
whole distro's store made the first message of a recording wait seconds on a loaded machine, and a killed
recorder then lost its first second)."""

from __future__ import annotations

from rosbags.typesys import Stores, get_typestore

from rostool.bag.crossver import CrossVersionStores

POSE = "geometry_msgs/msg/PoseStamped"


def _pose(store: object) -> object:
    types = store.types  # type: ignore[attr-defined]
    header = types["std_msgs/msg/Header"]
    time = types["builtin_interfaces/msg/Time"](sec=3, nanosec=4)
    fields = {"stamp": time, "frame_id": "map"}
    if "seq" in header.__dataclass_fields__:
        fields["seq"] = 9
    pose = types["geometry_msgs/msg/Pose"](
        position=types["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=3.0),
        orientation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    return types[POSE](header=header(**fields), pose=pose)


def test_ros1_to_cdr_and_back_carries_the_values_and_builds_only_the_types_used() -> None:
    ros1 = get_typestore(Stores.ROS1_NOETIC)
    ros2 = get_typestore(Stores.ROS2_JAZZY)
    to_ros2 = CrossVersionStores(2).store_for(ros1, POSE, POSE)
    cdr = to_ros2.ros1_to_cdr(ros1.serialize_ros1(_pose(ros1), POSE), POSE)
    got = ros2.deserialize_cdr(bytes(cdr), POSE)
    assert (got.header.stamp.sec, got.header.stamp.nanosec, got.header.frame_id) == (3, 4, "map")
    position, orientation = got.pose.position, got.pose.orientation
    assert (position.x, position.y, position.z, orientation.w) == (1, 2, 3, 1)
    assert set(to_ros2.fielddefs) == {
        POSE, "std_msgs/msg/Header", "geometry_msgs/msg/Pose", "geometry_msgs/msg/Point",
        "geometry_msgs/msg/Quaternion", "builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration",
    }  # fmt: skip

    # The other way, rosbags converts with the ROS 2 store; the ROS 1 store gives the definition and md5sum
    # a ROS 1 subscriber checks (geometry_msgs/PoseStamped's, as ROS 1's own tools compute it).
    to_ros1 = CrossVersionStores(1).store_for(ros2, POSE, POSE)
    assert to_ros1.generate_msgdef(POSE, ros_version=1)[1] == "d3812c3cbc69362b77dc0b19b345f8f5"
    back = ros1.deserialize_ros1(bytes(ros2.cdr_to_ros1(ros2.serialize_cdr(got, POSE), POSE)), POSE)
    assert (back.header.stamp.sec, back.header.frame_id, back.pose.position.y) == (3, "map", 2.0)


def test_a_renamed_type_is_built_under_its_new_name() -> None:
    """ROS 1's tf/tfMessage is recorded into ROS 2 bags as tf2_msgs/msg/TFMessage (rosbags' rename)."""
    from rosbags.typesys import get_types_from_msg

    src = get_typestore(Stores.ROS1_NOETIC)
    src.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf/msg/tfMessage"))
    store = CrossVersionStores(2).store_for(src, "tf/msg/tfMessage", "tf2_msgs/msg/TFMessage")
    assert "tf2_msgs/msg/TFMessage" in store.fielddefs
    assert [name for name, _desc in store.fielddefs["std_msgs/msg/Header"][1]] == ["stamp", "frame_id"]
