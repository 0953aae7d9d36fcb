"""ROS 2 wire conventions checked without a network: names, graph messages, discovery configuration."""

from __future__ import annotations

import pytest
from rosbags.typesys import Stores, get_typestore

from rostool.errors import RostoolError
from rostool.graph.ros2 import dds
from rostool.graph.ros2.discovery import NodeEntry, decode_entities_info, encode_entities_info
from rostool.graph.ros2_base import env, names, qos

GUID = bytes(range(1, 17))
READER = bytes(range(16, 32))
WRITER = bytes(range(32, 48))


def test_names_are_mangled_like_rmw() -> None:
    assert names.topic_to_dds("chatter") == "rt/chatter"
    assert names.request_topic("/add_two_ints") == "rq/add_two_intsRequest"
    assert names.reply_topic("/ns/add_two_ints") == "rr/ns/add_two_intsReply"
    assert names.from_dds_topic("rt/a/b") == ("topic", "/a/b")
    assert names.from_dds_topic("rq/addRequest") == ("request", "/add")
    assert names.from_dds_topic("ros_discovery_info") is None
    assert names.type_to_dds("std_msgs/msg/String") == "std_msgs::msg::dds_::String_"
    assert names.from_dds_type("example_interfaces::srv::dds_::AddTwoInts_Request_") == (
        "example_interfaces/srv/AddTwoInts_Request"
    )
    assert names.resolve("~/x", "/rostool_1") == "/rostool_1/x"


@pytest.mark.parametrize(("distro", "store"), [("jazzy", Stores.ROS2_JAZZY), ("humble", Stores.ROS2_HUMBLE)])
def test_participant_entities_info_matches_rosbags_cdr(distro: str, store: Stores) -> None:
    """Our graph message is exactly what rmw_dds_common's type serializes to, for 16- and 24-byte GIDs."""
    from rostool.graph.ros2.types import gid_size

    size = gid_size(distro)
    typestore = get_typestore(store)
    gid = typestore.types["rmw_dds_common/msg/Gid"]
    node = typestore.types["rmw_dds_common/msg/NodeEntitiesInfo"]
    info = typestore.types["rmw_dds_common/msg/ParticipantEntitiesInfo"]
    import numpy as np

    def as_gid(value: bytes) -> object:
        return gid(data=np.frombuffer(value.ljust(size, b"\0"), dtype=np.uint8))

    message = info(
        gid=as_gid(GUID),
        node_entities_info_seq=[
            node(node_namespace="/", node_name="talker", reader_gid_seq=[as_gid(READER)],
                 writer_gid_seq=[as_gid(WRITER), as_gid(READER)]),
            node(node_namespace="/robot", node_name="x", reader_gid_seq=[], writer_gid_seq=[]),
        ],
    )  # fmt: skip
    expected = bytes(typestore.serialize_cdr(message, "rmw_dds_common/msg/ParticipantEntitiesInfo"))
    nodes = [NodeEntry("/", "talker", [READER], [WRITER, READER]), NodeEntry("/robot", "x")]
    encoded = encode_entities_info(GUID, nodes, size)
    assert encoded.rstrip(b"\0") == expected.rstrip(b"\0")
    participant, decoded = decode_entities_info(expected)
    assert participant == GUID
    assert [(n.full_name, n.readers, n.writers) for n in decoded] == [
        ("/talker", [READER], [WRITER, READER]),
        ("/robot/x", [], []),
    ]


def test_discovery_range_follows_ros2() -> None:
    """ROS 2's default range is SUBNET (Cyclone's multicast); LOCALHOST stays on 127.0.0.1 unless static peers
    must be reached elsewhere (tests/test_across_machines.py checks each against a real node)."""
    default = dds.cyclone_config({})
    assert env.discovery_range({}) == "SUBNET"
    assert "AllowMulticast" not in default and "127.0.0.1" not in default and "<Peers>" not in default
    local = {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    config = dds.cyclone_config(local)
    assert '<NetworkInterface address="127.0.0.1"/>' in config and dds.loopback_only(local)
    assert "<AllowMulticast>false</AllowMulticast>" in config
    assert '<Peers><Peer address="127.0.0.1"/></Peers>' in config
    assert "<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>" in config
    far = {**local, "ROS_STATIC_PEERS": "198.18.2.20"}
    config = dds.cyclone_config(far)
    assert "NetworkInterface" not in config and not dds.loopback_only(far)  # the peer is elsewhere
    assert '<Peers><Peer address="127.0.0.1"/><Peer address="198.18.2.20"/></Peers>' in config
    subnet_peer = dds.cyclone_config({"ROS_STATIC_PEERS": "198.18.2.20; robot.local"})
    assert '<Peers><Peer address="198.18.2.20"/><Peer address="robot.local"/></Peers>' in subnet_peer
    assert "<ParticipantIndex>auto</ParticipantIndex>" in subnet_peer
    with_user = dds.cyclone_config({**local, "CYCLONEDDS_URI": "file:///etc/cyclone.xml"})
    assert with_user.endswith(",file:///etc/cyclone.xml")  # appended, so the user's settings win
    assert env.discovery_range({"ROS_LOCALHOST_ONLY": "0"}) == "SUBNET"
    assert env.discovery_range({"ROS_LOCALHOST_ONLY": "1", "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}) == (
        "LOCALHOST"
    )
    off = dds.cyclone_config({"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF", "ROS_STATIC_PEERS": "198.18.2.20"})
    assert "<Tag>ros_discovery_off_" in off and "198.18.2.20" not in off


@pytest.mark.parametrize("value", ["-1", "233", "x"])
def test_domain_id_out_of_range(value: str) -> None:
    with pytest.raises(RostoolError, match="ROS_DOMAIN_ID"):
        env.domain_id({"ROS_DOMAIN_ID": value})


def test_qos_adaptation_follows_ros2cli() -> None:
    reliable = qos.QosProfile("reliable", "transient_local", 1)
    best_effort = qos.QosProfile("best_effort", "volatile", 5)
    assert qos.adapt_to_publishers(qos.QosRequest(), [reliable])[0] == qos.QosProfile(
        "reliable", "transient_local", 10
    )
    mixed, notes = qos.adapt_to_publishers(qos.QosRequest(), [reliable, best_effort])
    assert mixed == qos.QosProfile("best_effort", "volatile", 10) and len(notes) == 2
    forced, _ = qos.adapt_to_publishers(qos.QosRequest(reliability="reliable", depth=3), [best_effort])
    assert forced == qos.QosProfile("reliable", "volatile", 3)


def test_our_serialized_messages_equal_real_ros2_bytes() -> None:
    """What rostool publishes is what a real ROS 2 talker sent (bytes recorded by rosbag2)."""
    from rostool.bag.reader import BagReader
    from rostool.graph.ros2.types import TypeSupport
    from tests.support import TESTDATA

    types = TypeSupport("jazzy")
    with BagReader([TESTDATA / "ros2" / "talker_mcap"]) as reader:
        recorded = [bytes(raw) for conn, _t, raw in reader.messages() if conn.topic == "/topic"]
    assert recorded
    for index, raw in enumerate(recorded):
        message = types.store.types["std_msgs/msg/String"](data=f"Hello, world! {index}")
        assert types.serialize(message, "std_msgs/msg/String") == raw


def test_announcements_of_any_shape_read_safely() -> None:
    """doctor reads other machines' SPDP datagrams: any bytes give a release or None, never an exception."""
    import random

    from rostool.graph.ros2_base.spdp import product_version, release

    header = b"RTPS\x02\x02\x01\x0f" + bytes(12)
    chance = random.Random(36)
    for _ in range(3000):
        body = bytes(chance.randrange(256) for _ in range(chance.randrange(80)))
        message = header + bytes([0x15, chance.randrange(4)]) + body
        assert product_version(message) is None or len(product_version(message) or ()) == 3
        assert release(message).startswith("Fast DDS")
    truncated = header + b"\x15\x01\xff\xff"  # a length past the end
    assert product_version(truncated) is None
