"""Custom .msg/.srv/.action types from source trees: md5sums and texts against Debian's genmsg/genpy,
workspace discovery, and clear errors for malformed files or types found nowhere."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support import (
    DEBIAN_PYTHON,
    debian,
    debian_env,
    interface_workspace,
    require_ros1_peers,
    rostool,
    with_genpy_classes,
)

SUM_SRV = "int64 a\nint64 b\n---\nint64 sum\n"
MOVE_ACTION = (
    "# Goal\ngeometry_msgs/Point point\n---\n# Result\nfloat32 elapsed_time\n---\n"
    "# Feedback\nfloat32 distance_to_point\n"
)
# Every corner of genmsg's md5 rules: constants first with their written value (1e-3 stays 1e-3, a
# string keeps its `#`), char/byte, time/duration, fixed and variable arrays, Header, a type of the same
# package named without its package, and built-in nested types.
WAYPOINT_MSG = """# A waypoint   (comments and spacing never count)
Header header
float64 TOLERANCE = 1e-3
string   LABEL=  dock # not a comment
int8 LOW=-128
uint64 BIG=18446744073709551615
bool ENABLED=True
char letter
byte raw
time   arrive_by
duration[2] windows
Tag[] tags
geometry_msgs/Point[3] corners
  uint8[]   payload
"""
TAG_MSG = "string name\nint32 id\n"
PLAN_SRV = """# Plan a route
Waypoint start
Waypoint[] via
string MODE_FAST=fast
---
bool ok
Tag[] used
geometry_msgs/Point goal
"""
GENPY_MD5 = """
import sys, json, importlib
out = {}
for name in sys.argv[1:]:
    pkg, kind, typ = name.split("/")
    cls = getattr(importlib.import_module(pkg + "." + kind), typ)
    out[name] = cls._md5sum
print(json.dumps(out))
"""


@pytest.fixture
def custom_env(tmp_path: Path) -> dict[str, str]:
    """A source tree with the book's service and action plus richer types, and genpy classes for them."""
    require_ros1_peers()
    src = interface_workspace(
        tmp_path / "ws",
        {
            "sum_two_numbers/srv/SumTwoInts.srv": SUM_SRV,
            "robot_navigation_pkg/action/MoveToPoint.action": MOVE_ACTION,
            "route_pkg/msg/Waypoint.msg": WAYPOINT_MSG,
            "route_pkg/msg/Tag.msg": TAG_MSG,
            "route_pkg/srv/Plan.srv": PLAN_SRV,
        },
    )
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["ROS_HOME"] = str(home)
    return with_genpy_classes(env, src, tmp_path)


def _genpy_md5(env: dict[str, str], *names: str) -> dict[str, str]:
    done = debian([DEBIAN_PYTHON, "-c", GENPY_MD5, *names], env)
    assert done.returncode == 0, done.stderr
    result: dict[str, str] = json.loads(done.stdout)
    return result


def test_custom_msg_srv_action_md5_match_genpy(custom_env: dict[str, str]) -> None:
    env = custom_env
    suffixes = ("Action", "Goal", "Result", "Feedback", "ActionGoal", "ActionResult", "ActionFeedback")
    messages = [
        "route_pkg/Waypoint",
        "route_pkg/Tag",
        *(f"robot_navigation_pkg/MoveToPoint{s}" for s in suffixes),
    ]
    services = ["sum_two_numbers/SumTwoInts", "route_pkg/Plan"]
    theirs = _genpy_md5(
        env,
        *(f"{n.split('/')[0]}/msg/{n.split('/')[1]}" for n in messages),
        *(
            f"{n.split('/')[0]}/srv/{n.split('/')[1]}{part}"
            for n in services
            for part in ("", "Request", "Response")
        ),
    )
    for name in messages:
        ours = rostool(["msg", "md5", name], env)
        assert ours.stdout.strip() == theirs[f"{name.split('/')[0]}/msg/{name.split('/')[1]}"], (
            name,
            ours.stderr,
        )
    for name in services:
        pkg, typ = name.split("/")
        assert rostool(["srv", "md5", name], env).stdout.strip() == theirs[f"{pkg}/srv/{typ}"], name
        for part in ("Request", "Response"):
            ours = rostool(["msg", "md5", f"{name}{part}"], env)
            assert ours.stdout.strip() == theirs[f"{pkg}/srv/{typ}{part}"], (name, part, ours.stderr)
    assert theirs["sum_two_numbers/srv/SumTwoInts"] == "6a2e34150c00229791cc89ff309fff21"


def test_builtin_services_match_debian_classes(custom_env: dict[str, str]) -> None:
    env = custom_env
    names = ["std_srvs/Empty", "std_srvs/Trigger", "std_srvs/SetBool", "roscpp/GetLoggers",
             "roscpp/SetLoggerLevel", "roscpp/Empty"]  # fmt: skip
    theirs = _genpy_md5(env, *(n.replace("/", "/srv/") for n in names))
    for name in names:
        assert rostool(["srv", "md5", name], env).stdout.strip() == theirs[name.replace("/", "/srv/")], name
    # the texts shipped in rostool are Debian's own .srv files
    for name in ("Empty", "Trigger", "SetBool"):
        shipped = Path(f"/usr/share/std_srvs/srv/{name}.srv")
        if shipped.exists():
            assert (
                rostool(["srv", "show", f"std_srvs/{name}", "--raw"], env).stdout
                == shipped.read_text() + "\n"
            )
    trigger = rostool(["srv", "show", "std_srvs/Trigger"], env).stdout
    assert trigger == "---\nbool success\nstring message\n\n"


def test_genaction_expansion_matches_debian_move_base_msgs(tmp_path: Path) -> None:
    """move_base_msgs was built by catkin's genaction: an independent check of our expansion."""
    require_ros1_peers()
    probe = """
import json, move_base_msgs.msg as m
sep = "\\n" + "=" * 80 + "\\n"
names = ["MoveBase" + s for s in ("Action", "Goal", "Result", "Feedback", "ActionGoal", "ActionResult",
                                   "ActionFeedback")]
print(json.dumps({n: [getattr(m, n)._md5sum, getattr(m, n)._full_text.split(sep)[0]] for n in names}))
"""
    done = debian([DEBIAN_PYTHON, "-c", probe], {})
    if done.returncode != 0:
        pytest.skip("Debian's python3-move-base-msgs is not installed")
    theirs = json.loads(done.stdout)
    action = "geometry_msgs/PoseStamped target_pose\n---\n---\ngeometry_msgs/PoseStamped base_position\n"
    interface_workspace(tmp_path / "ws", {"move_base_msgs/action/MoveBase.action": action})
    for name, (md5, _text) in theirs.items():
        ours = rostool(["msg", "md5", f"move_base_msgs/{name}", "--interfaces", str(tmp_path / "ws")], {})
        assert ours.stdout.strip() == md5, (name, ours.stderr)
    from rostool.interfaces.sources import Interfaces

    catalog = Interfaces([tmp_path / "ws"], roots=None)
    for name, (_md5, text) in theirs.items():
        assert catalog.full_text(f"move_base_msgs/{name}").split("\n" + "=" * 80 + "\n")[0] == text, name


def test_show_matches_rossrv_and_rosmsg(custom_env: dict[str, str]) -> None:
    env = custom_env
    for name in ("sum_two_numbers/SumTwoInts",):
        ours = rostool(["srv", "show", name], env)
        theirs = debian(["rossrv", "show", name], env)
        assert theirs.returncode == 0, theirs.stderr
        assert ours.stdout == theirs.stdout == "int64 a\nint64 b\n---\nint64 sum\n\n"
    bare_ours, bare_theirs = (
        rostool(["srv", "show", "SumTwoInts"], env),
        debian(["rossrv", "show", "SumTwoInts"], env),
    )
    assert bare_ours.stdout == bare_theirs.stdout
    assert (
        rostool(["msg", "show", "route_pkg/Tag"], env).stdout
        == debian(["rosmsg", "show", "route_pkg/Tag"], env).stdout
    )
    waypoint = rostool(["msg", "show", "route_pkg/Waypoint"], env).stdout.splitlines()
    assert waypoint[:12] == [
        "float64 TOLERANCE=1e-3", "string LABEL=dock # not a comment", "int8 LOW=-128",
        "uint64 BIG=18446744073709551615", "bool ENABLED=True", "std_msgs/Header header", "  uint32 seq",
        "  time stamp", "  string frame_id", "char letter", "byte raw", "time arrive_by",
    ]  # fmt: skip
    assert "route_pkg/Tag[] tags" in waypoint and "geometry_msgs/Point[3] corners" in waypoint
    action = rostool(["action", "show", "robot_navigation_pkg/MoveToPoint"], env).stdout
    assert action == (
        "geometry_msgs/Point point\n  float64 x\n  float64 y\n  float64 z\n---\nfloat32 elapsed_time\n---\n"
        "float32 distance_to_point\n\n"
    )
    listed = rostool(["msg", "list"], env).stdout.split()
    assert {"route_pkg/Waypoint", "robot_navigation_pkg/MoveToPointActionGoal", "std_msgs/String"} <= set(
        listed
    )
    assert "sum_two_numbers/SumTwoInts" in rostool(["srv", "list"], env).stdout.split()
    assert json.loads(rostool(["srv", "list", "--json"], env).stdout).count("std_srvs/Trigger") == 1


def _run_in(cwd: Path, args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rostool", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=30)  # fmt: skip


def test_sources_workspace_interfaces_option_and_env(tmp_path: Path) -> None:
    src = interface_workspace(tmp_path / "catkin_ws", {"sum_two_numbers/srv/SumTwoInts.srv": SUM_SRV})
    # package.xml names the package, whatever the folder is called
    renamed = tmp_path / "other" / "folder_name"
    (renamed / "srv").mkdir(parents=True)
    (renamed / "srv" / "AddInts.srv").write_text(SUM_SRV)
    (renamed / "package.xml").write_text("<package><name>real_name</name></package>")
    bare = tmp_path / "bare_pkg" / "msg"  # no package.xml: the folder names the package
    bare.mkdir(parents=True)
    (bare / "Note.msg").write_text("string text\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    md5 = ["srv", "md5", "sum_two_numbers/SumTwoInts"]
    expected = "6a2e34150c00229791cc89ff309fff21\n"
    assert _run_in(src / "sum_two_numbers" / "srv", md5, env).stdout == expected  # inside the workspace
    assert _run_in(tmp_path / "catkin_ws", md5, env).stdout == expected
    outside = _run_in(tmp_path, md5, env)
    assert outside.returncode == 1 and "unknown service type sum_two_numbers/SumTwoInts" in outside.stderr
    assert _run_in(tmp_path, [*md5, "--interfaces", str(tmp_path / "catkin_ws")], env).stdout == expected
    assert _run_in(tmp_path, [*md5, "--interfaces", str(src / "sum_two_numbers")], env).stdout == expected
    one_file = str(src / "sum_two_numbers" / "srv" / "SumTwoInts.srv")
    assert _run_in(tmp_path, [*md5, "--interfaces", one_file], env).stdout == expected
    assert _run_in(tmp_path, md5, {**env, "ROS_PACKAGE_PATH": str(src)}).stdout == expected
    assert _run_in(tmp_path, md5, {**env, "ROSTOOL_INTERFACES": str(src)}).stdout == expected
    renamed_md5 = _run_in(
        tmp_path, ["srv", "md5", "real_name/AddInts", "--interfaces", str(tmp_path / "other")], env
    )
    assert renamed_md5.stdout == expected, renamed_md5.stderr
    note = _run_in(
        tmp_path, ["msg", "show", "bare_pkg/Note", "--interfaces", str(tmp_path / "bare_pkg")], env
    )
    assert note.stdout == "string text\n\n", note.stderr


def test_type_not_found_says_where_it_looked(tmp_path: Path) -> None:
    src = interface_workspace(tmp_path / "ws", {"sum_two_numbers/srv/SumTwoInts.srv": SUM_SRV})
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["ROS_PACKAGE_PATH"] = str(tmp_path / "elsewhere")
    missing = _run_in(tmp_path, ["srv", "show", "sum_two_numbers/Missing", "--interfaces", str(src)], env)
    assert missing.returncode == 1
    line = missing.stderr.strip()
    assert len(missing.stderr.splitlines()) == 1 and "Traceback" not in missing.stderr
    assert f"package sum_two_numbers (at {src / 'sum_two_numbers'}) has no srv/Missing.srv" in line
    assert f"--interfaces {src}" in line and f"ROS_PACKAGE_PATH {tmp_path / 'elsewhere'}" in line
    nowhere = _run_in(tmp_path, ["action", "show", "nav_pkg/Go"], env)
    assert (
        nowhere.returncode == 1
        and "unknown action type nav_pkg/Go: no package nav_pkg found" in nowhere.stderr
    )
    msg = _run_in(tmp_path, ["msg", "md5", "nav_pkg/Pose"], env)
    assert msg.returncode == 1 and "built-in ROS 1 types" in msg.stderr


@pytest.mark.parametrize(
    ("relative", "text", "expected"),
    [
        ("p/srv/Bad.srv", "int64 a\nint64 b extra\n---\nint64 sum\n", "Bad.srv:2: expected `TYPE NAME`"),
        ("p/srv/Bad.srv", "int64 a\n---\n# result\nint 64x sum\n", "Bad.srv:4: expected `TYPE NAME`"),
        ("p/srv/Bad.srv", "int64 a\n---\nin-t64 sum\n", "Bad.srv:3: 'in-t64' is not a legal field type"),
        ("p/srv/Bad.srv", "int8 LIMIT=300\n---\n", "Bad.srv:1: constant value 300 does not fit a int8"),
        ("p/srv/Bad.srv", "time STAMP=3\n---\n", "Bad.srv:1: 'time' cannot be a constant type"),
        ("p/srv/Bad.srv", "int64 a\nint64 a\n---\n", "Bad.srv:2: field 'a' is declared twice"),
        (
            "p/action/Bad.action",
            "int64 a\n---\nint64 b\n",
            "Bad.action:3: an .action file has three sections",
        ),
        ("p/action/Bad.action", "a/b/c x\n---\n---\n", "Bad.action:1: 'a/b/c' is not a legal field type"),
        ("p/action/Bad.action", "int64 a\n---\n---\nint64 f\n---\nint64 g\n", "Bad.action:5: an .action"),
        (
            "p/action/Bad.action",
            "---\n---\nfloat32 X=abc\n",
            "Bad.action:3: constant value 'abc' is not a float32",
        ),
    ],
)
def test_malformed_files_name_file_and_line(tmp_path: Path, relative: str, text: str, expected: str) -> None:
    src = interface_workspace(tmp_path / "ws", {relative: text})
    kind = "srv" if relative.endswith(".srv") else "action"
    done = rostool([kind, "show", "p/Bad", "--interfaces", str(src)], {**os.environ, "ROS_PACKAGE_PATH": ""})
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.startswith(f"rostool: {src / relative.rsplit('/', 1)[0]}/"), done.stderr
    assert expected in done.stderr and len(done.stderr.splitlines()) == 1, done.stderr


def test_debian_env_sees_generated_classes(custom_env: dict[str, str]) -> None:
    """The peers' side of the setup: Debian's tools import the generated classes."""
    probe = "from sum_two_numbers.srv import SumTwoInts; print(SumTwoInts._type)"
    done = subprocess.run(
        [DEBIAN_PYTHON, "-c", probe], env=debian_env(custom_env), capture_output=True, text=True
    )
    assert done.stdout.strip() == "sum_two_numbers/SumTwoInts", done.stderr


def test_service_and_action_verbs_say_ros1_only_on_ros2() -> None:
    for verb in (["service", "uri", "/x"], ["service", "node", "/x"]):
        done = rostool(["--ros2", *verb], {**os.environ})
        assert done.returncode == 1 and done.stdout == ""
        assert done.stderr.endswith(": supported on ROS 1 graphs only in this rostool version; use --ros1 "
                                    "(or set ROS_MASTER_URI) with a ROS 1 master\n"), done.stderr  # fmt: skip
