"""Unknown ROS 2 types learned from the publisher's node (REP 2016 `<node>/get_type_description`): rostool
serves the description of what it publishes, and echo/record without interface sources decode it."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rostool.bag.reader import BagReader
from rostool.graph.ros2 import type_description as td
from rostool.interfaces.typestores import builtin_store
from tests.support import interface_workspace, rostool, rostool_popen, stop
from tests.test_ros2_graph import ros2_env
from tests.test_ros2_interfaces import SOURCES

STATUS = "{name: r2, parts: [{label: arm, weight: 1.5}, {label: leg}], where: {x: 1.0, z: -2.5}}"
SERVICE_TYPE = "type_description_interfaces/srv/GetTypeDescription"

# Publishes robo_msgs/msg/Part on /raw from a bare DDS writer of rostool's Session; argv: sources, mode.
# mode "silent" serves no type description (as a Humble node or a node of another RMW); "tampered" serves
# one whose `weight` is float32 instead of float64.
RAW_NODE = r"""
import sys, time
from cyclonedds._clayer import ddspy_write
from rostool.graph.ros2 import type_description
from rostool.graph.ros2_base.qos import PROFILES
from rostool.graph.ros2.graph import Ros2Graph
from rostool.graph.ros2_base.names import topic_to_dds
from rostool.interfaces.fill import build_message

graph = Ros2Graph("raw", anonymous=False, interface_paths=[sys.argv[1]])
types = graph.types
part = types.store_name("robo_msgs/msg/Part")
writer = graph.session.writer(topic_to_dds("/raw"), part, PROFILES["default"])

class Tampered(type_description.TypeDescriptionServer):
    def describe(self, type_name):
        found = super().describe(type_name)
        found["type_description"]["fields"][1]["type"]["type_id"] = 10
        return found

server = Tampered(graph.session, graph.node_name) if sys.argv[2] == "tampered" else None
payload = types.serialize(build_message(types.store, part, {"label": "raw", "weight": 2.0}), part)
print("ready", flush=True)
while True:
    ddspy_write(writer._ref, payload)
    time.sleep(0.1)
"""


@pytest.fixture
def sources(tmp_path: Path) -> Path:
    return interface_workspace(tmp_path / "ws", SOURCES)


@pytest.fixture
def status_publisher(sources: Path) -> Iterator[dict[str, str]]:
    """rostool publishing robo_msgs/msg/Status at 10 Hz, the type known only from `sources`."""
    env = ros2_env()
    proc = rostool_popen(
        ["topic", "pub", "/status", "robo_msgs/msg/Status", STATUS, "-r", "10", "--interfaces", str(sources)],
        env,
    )
    yield env
    stop(proc)


def start_raw(sources: Path, mode: str) -> tuple[subprocess.Popen[str], dict[str, str]]:
    env = ros2_env()
    proc = subprocess.Popen(
        [sys.executable, "-c", RAW_NODE, str(sources), mode], env=env, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert proc.stdout is not None
    assert proc.stdout.readline() == "ready\n", proc.stderr.read() if proc.stderr else ""
    return proc, env


EXPECTED_STATUS = {
    "name": "r2",
    "parts": [{"label": "arm", "weight": 1.5}, {"label": "leg", "weight": 0.5}],  # 0.5: the .msg default
    "where": {"x": 1.0, "y": 0.0, "z": -2.5},
}


def test_echo_decodes_a_type_only_the_publisher_knows(
    status_publisher: dict[str, str], tmp_path: Path
) -> None:
    env = status_publisher
    echoed = rostool(["topic", "echo", "/status", "-n", "2", "--json"], env, cwd=tmp_path)
    assert echoed.returncode == 0, echoed.stderr
    lines = echoed.stdout.splitlines()
    assert [json.loads(line) for line in lines] == [EXPECTED_STATUS, EXPECTED_STATUS]

    yaml = rostool(["topic", "echo", "/status", "-n", "1", "--field", "parts"], env, cwd=tmp_path)
    assert "label: leg" in yaml.stdout and "weight: 0.5" in yaml.stdout, yaml.stderr


def test_record_stores_a_type_only_the_publisher_knows(
    status_publisher: dict[str, str], tmp_path: Path
) -> None:
    out = tmp_path / "learned.mcap"
    recorded = rostool(["bag", "record", "/status", "-O", str(out), "--duration", "2.5"], status_publisher,
                       cwd=tmp_path)  # fmt: skip
    assert recorded.returncode == 0, recorded.stderr
    assert "recorded 0 messages" not in recorded.stderr and "unknown" not in recorded.stderr
    with BagReader([out]) as reader:
        conns = reader.select(["/status"])
        assert [c.msgtype for c in conns] == ["robo_msgs/msg/Status"]
        messages = [reader.deserialize(raw, conn) for conn, _stamp, raw in reader.messages(conns)]
    assert messages
    first: Any = messages[0]
    assert (first.name, [p.label for p in first.parts], [p.weight for p in first.parts]) == (
        "r2", ["arm", "leg"], [1.5, 0.5]
    )  # fmt: skip
    assert (first.where.x, first.where.z) == (1.0, -2.5)


def test_the_service_answers_for_used_types_only(status_publisher: dict[str, str], tmp_path: Path) -> None:
    env = status_publisher
    nodes = rostool(["node", "list"], env).stdout.split()
    publisher = next(n for n in nodes if n.startswith("/rostool_"))
    service = f"{publisher}/get_type_description"
    assert service in rostool(["service", "list"], env).stdout

    def ask(request: str) -> dict[str, object]:
        called = rostool(["service", "call", service, SERVICE_TYPE, request, "--json"], env, cwd=tmp_path)
        assert called.returncode == 0, called.stderr
        return json.loads(called.stdout)  # type: ignore[no-any-return]

    found = ask("{type_name: robo_msgs/msg/Status}")
    assert found["successful"] is True, found
    description = found["type_description"]
    assert isinstance(description, dict)
    assert description["type_description"]["type_name"] == "robo_msgs/msg/Status"
    fields = {f["name"]: f["type"] for f in description["type_description"]["fields"]}
    parts = {
        key: fields["parts"][key] for key in ("type_id", "capacity", "string_capacity", "nested_type_name")
    }
    assert parts == {
        "type_id": 145,
        "capacity": 0,
        "string_capacity": 0,
        "nested_type_name": "robo_msgs/msg/Part",
    }
    assert [d["type_name"] for d in description["referenced_type_descriptions"]] == [
        "geometry_msgs/msg/Point", "robo_msgs/msg/Part",
    ]  # fmt: skip

    unused = ask("{type_name: geometry_msgs/msg/Pose}")
    assert unused["successful"] is False and "not used by this node" in str(unused["failure_reason"])
    wrong_hash = ask("{type_name: robo_msgs/msg/Status, type_hash: RIHS01_00}")
    assert wrong_hash["successful"] is False and "not RIHS01_00" in str(wrong_hash["failure_reason"])


def echo_raw(sources: Path, mode: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """`topic echo /raw` (no interface sources) against a raw publisher in `mode`."""
    proc, env = start_raw(sources, mode)
    try:
        return rostool(["topic", "echo", "/raw", "-n", "1"], env, cwd=cwd)
    finally:
        proc.kill()
        proc.communicate()


def test_a_publisher_without_the_service_keeps_the_unknown_type_error(sources: Path, tmp_path: Path) -> None:
    echoed = echo_raw(sources, "silent", tmp_path)
    assert echoed.returncode == 1 and echoed.stderr.count("\n") == 1, echoed.stderr
    assert "unknown message type 'robo_msgs/msg/Part'" in echoed.stderr
    reason = "The publisher did not provide its type description (/raw: the node does not serve"
    assert reason in echoed.stderr


def test_a_description_that_does_not_hash_to_the_announced_hash_is_refused(
    sources: Path, tmp_path: Path
) -> None:
    echoed = echo_raw(sources, "tampered", tmp_path)
    assert echoed.returncode == 1 and echoed.stderr.count("\n") == 1, echoed.stderr
    assert "unknown message type 'robo_msgs/msg/Part'" in echoed.stderr
    assert "the description of robo_msgs/msg/Part hashes to RIHS01_" in echoed.stderr
    assert "not to the announced RIHS01_" in echoed.stderr and "Traceback" not in echoed.stderr


# --- description <-> rosbags definitions, without DDS ----------------------------------------------------


@pytest.mark.parametrize(
    "type_name",
    [
        "geometry_msgs/msg/PoseStamped",
        "sensor_msgs/msg/PointCloud2",
        "geometry_msgs/msg/PoseWithCovariance",  # float64[36]
        "type_description_interfaces/msg/FieldType",  # string<=255
        "std_msgs/msg/Empty",  # rosidl's placeholder member
    ],
)
def test_description_round_trips_to_the_same_hash(type_name: str) -> None:
    from rosbags.typesys import Stores, get_typestore

    store = builtin_store("jazzy")
    typs = td.to_fielddefs(td.describe(store.fielddefs, type_name))
    scratch = get_typestore(Stores.EMPTY)
    scratch.register(typs)
    assert scratch.hash_rihs01(type_name) == store.hash_rihs01(type_name)
    assert td.verified(typs, type_name, store.hash_rihs01(type_name), store) == {}


def test_every_store_type_and_field_kind_round_trips() -> None:
    from rosbags.typesys import Stores, get_typestore

    store = builtin_store("jazzy")
    learned: dict[str, object] = {}
    kinds: set[int] = set()
    for name in store.fielddefs:
        description = td.describe(store.fielddefs, name)
        kinds.update(f["type"]["type_id"] for f in description["type_description"]["fields"])
        learned.update(td.to_fielddefs(description))
    scratch = get_typestore(Stores.EMPTY)
    scratch.register(learned)  # type: ignore[arg-type]
    assert all(scratch.hash_rihs01(name) == store.hash_rihs01(name) for name in store.fielddefs)
    assert {1, 17, 21, 59, 97, 145, 161} <= kinds  # nested, strings, arrays, bounded and unbounded sequences


def test_bounded_sequences_and_string_arrays_map_exactly() -> None:
    from rosbags.interfaces import Nodetype
    from rosbags.typesys import get_types_from_msg

    typs = get_types_from_msg("int32[<=3] few\nstring<=4[2] tags\nbyte[] raw\nchar c\n", "demo_msgs/msg/Mix")
    description = td.describe(typs, "demo_msgs/msg/Mix")
    ids = [(f["type"]["type_id"], f["type"]["capacity"], f["type"]["string_capacity"])
           for f in description["type_description"]["fields"]]  # fmt: skip
    assert ids == [(102, 3, 0), (69, 2, 4), (160, 0, 0), (13, 0, 0)]
    assert td.to_fielddefs(description)["demo_msgs/msg/Mix"][1] == [
        ("few", (Nodetype.SEQUENCE, ((Nodetype.BASE, ("int32", 0)), 3))),
        ("tags", (Nodetype.ARRAY, ((Nodetype.BASE, ("string", 4)), 2))),
        ("raw", (Nodetype.SEQUENCE, ((Nodetype.BASE, ("byte", 0)), 0))),
        ("c", (Nodetype.BASE, ("char", 0))),
    ]


def field_type(type_id: int, nested: str = "") -> dict[str, object]:
    return {"type_id": type_id, "capacity": 0, "string_capacity": 0, "nested_type_name": nested}


@pytest.mark.parametrize(
    ("change", "complaint"),
    [
        ({"name": "__import__('os')"}, "not a valid field name"),
        ({"type": field_type(18)}, "wstring"),
        ({"type": field_type(1, "x")}, "pkg/msg/Name"),
        ({"type": field_type(200)}, "id 200"),
    ],
)
def test_unusable_descriptions_are_refused(change: dict[str, object], complaint: str) -> None:
    store = builtin_store("jazzy")
    description = td.describe(store.fielddefs, "std_msgs/msg/String")
    description["type_description"]["fields"][0].update(change)
    with pytest.raises(td.DescriptionError, match=complaint.replace("(", r"\(")):
        td.to_fielddefs(description)


def test_a_description_missing_a_referenced_type_is_refused() -> None:
    store = builtin_store("jazzy")
    description = td.describe(store.fielddefs, "geometry_msgs/msg/PoseStamped")
    description["referenced_type_descriptions"].pop()
    with pytest.raises(td.DescriptionError, match="lacks the referenced type"):
        td.to_fielddefs(description)
