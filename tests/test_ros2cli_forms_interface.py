# ruff: noqa: E501  (expected ros2cli lines are kept whole)
"""ros2cli's own ros2interface test cases (ros2interface/test/test_cli.py), run against `rostool interface`.

The command lines and expected lines are ros2cli's, taken as facts. test_msgs comes from a ROS 2 install
(AMENT_PREFIX_PATH: the Jazzy peer venv's share/); ros2cli_test_interfaces' ShortVaried* files are
rebuilt from the expected --all-comments output, in a source tree given with --interfaces. No graph.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from tests.ros2_peers import PEERS_DIR, peer_python
from tests.support import interface_workspace, rostool
from tests.test_ros2cli_forms import Cases

SOME_MESSAGES = ["test_msgs/msg/BasicTypes", "test_msgs/msg/Constants", "test_msgs/msg/Strings"]
SOME_SERVICES = ["test_msgs/srv/Arrays", "test_msgs/srv/BasicTypes", "test_msgs/srv/Empty"]
SOME_ACTIONS = ["test_msgs/action/Fibonacci"]
NAME_LINE = re.compile(r"\s*[A-z0-9_]+(/[A-z0-9_]+)+")
PKG = "ros2cli_test_interfaces"
SOURCES = {
    f"{PKG}/msg/ShortVaried.msg": "# A constant\nbool BOOL_CONST=true # Comment - Nesting Level 1: 1 of 2\n\n"
    "# Bool and array of bools\nbool bool_value\nbool[<=3] bool_values # Comment - Nesting Level 1: 2 of 2\n\n"
    "# Trailing comment\n",
    f"{PKG}/msg/ShortVariedNested.msg": "# A short, varied type\nShortVaried short_varied # Comment - Nesting Level 2: 1 of 1\n"
    "# Trailing comment\n",
    f"{PKG}/msg/ShortVariedMultiNested.msg": "# A short, varied, and nested type\n"
    "ShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 1\n# Trailing comment\n",
    f"{PKG}/srv/ShortVariedMultiNested.srv": "# Request\nShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 2\n"
    "---\n# Response\nbool bool_value # Comment - Nesting Level 3: 2 of 2\n",
    f"{PKG}/action/ShortVariedMultiNested.action": "# Goal definition\n"
    "ShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 2\n---\n# Result definition\n"
    "bool bool_value # Comment - Nesting Level 3: 2 of 2\n---\n# Feedback definition\nbool[3] bool_values\n",
}
NESTED = ["ShortVariedNested short_varied_nested", "\tShortVaried short_varied", "\t\tbool BOOL_CONST=true",
          "\t\tbool bool_value", "\t\tbool[<=3] bool_values"]  # fmt: skip


@pytest.fixture
def interface_env(tmp_path: Path) -> dict[str, str]:
    peer_python("jazzy")  # the ROS 2 install whose share/ holds test_msgs
    import os

    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS") and k != "AMENT_PREFIX_PATH"}
    return {**env, "AMENT_PREFIX_PATH": str(PEERS_DIR / "jazzy")}


def interface(env: dict[str, str], *args: str, stdin: str | None = None) -> Any:
    return rostool(["interface", *args], env, input=stdin)


def test_interface_cases(interface_env: dict[str, str], tmp_path: Path) -> None:
    env, c = interface_env, Cases()
    lines = interface(env, "list").stdout.splitlines()
    names = [line for line in lines if line not in ("Messages:", "Services:", "Actions:")]
    c.check("test_list_interfaces", all(NAME_LINE.fullmatch(x) for x in names)
            and all(f"    {n}" in names for n in SOME_MESSAGES + SOME_SERVICES + SOME_ACTIONS), lines[:5])  # fmt: skip
    for flag, title, some in (("-m", "Messages:", SOME_MESSAGES), ("-s", "Services:", SOME_SERVICES),
                              ("-a", "Actions:", SOME_ACTIONS)):  # fmt: skip
        lines = interface(env, "list", flag).stdout.splitlines()
        c.check(f"test_list_{title[:-1].lower()}", lines[0] == title and all(NAME_LINE.fullmatch(x) for x in lines[1:])
                and all(f"    {n}" in lines for n in some), lines[:5])  # fmt: skip
    got = interface(env, "package", "not_a_package")
    c.check(
        "test_package_on_nonexistent_package",
        got.returncode == 1 and "Unknown package 'not_a_package'" in got.stderr,
        got,
    )
    lines = interface(env, "package", "test_msgs").stdout.splitlines()
    c.check("test_package_on_test_msgs", all(re.fullmatch(r"test_msgs/(msg|srv|action)/[A-z0-9_]+", x) for x in lines)
            and all(n in lines for n in SOME_MESSAGES + SOME_SERVICES + SOME_ACTIONS), lines[:5])  # fmt: skip
    for flags, case in (([], "test_packages"), (["-m"], "test_packages_with_messages"),
                        (["-s"], "test_packages_with_services"), (["-a"], "test_packages_with_actions")):  # fmt: skip
        lines = interface(env, "packages", *flags).stdout.splitlines()
        c.check(case, "test_msgs" in lines, lines)
    src = interface_workspace(tmp_path / "ws", SOURCES)
    show = ["show", "--interfaces", str(src)]
    got = interface(env, *show, f"{PKG}/msg/ShortVariedMultiNested", "--no-comments")
    c.check("test_show_message_with_no_comments", got.stdout.splitlines() == NESTED, got)
    got = interface(env, *show, f"{PKG}/srv/ShortVariedMultiNested", "--no-comments")
    c.check(
        "test_show_service_with_no_comments",
        got.stdout.splitlines() == [*NESTED, "---", "bool bool_value"],
        got,
    )
    got = interface(env, *show, f"{PKG}/action/ShortVariedMultiNested", "--no-comments")
    c.check("test_show_action_with_no_comments", got.stdout.splitlines()
            == [*NESTED, "---", "bool bool_value", "---", "bool[3] bool_values"], got)  # fmt: skip
    got = interface(env, *show, f"{PKG}/msg/ShortVariedMultiNested")
    c.check("test_show_message", got.stdout.splitlines() == [
        "# A short, varied, and nested type", "ShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 1",
        *NESTED[1:], "# Trailing comment"], got)  # fmt: skip
    got = interface(env, *show, f"{PKG}/msg/ShortVariedMultiNested", "--all-comments")
    c.check("test_show_message_with_all_comments", got.stdout.splitlines() == [
        "# A short, varied, and nested type", "ShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 1",
        "\t# A short, varied type", "\tShortVaried short_varied # Comment - Nesting Level 2: 1 of 1",
        "\t\t# A constant", "\t\tbool BOOL_CONST=true # Comment - Nesting Level 1: 1 of 2", "",
        "\t\t# Bool and array of bools", "\t\tbool bool_value", "\t\tbool[<=3] bool_values # Comment - Nesting Level 1: 2 of 2",
        "", "\t\t# Trailing comment", "\t# Trailing comment", "# Trailing comment"], got)  # fmt: skip
    got = interface(env, *show, f"{PKG}/srv/ShortVariedMultiNested")
    c.check("test_show_service", got.stdout.splitlines() == [
        "# Request", "ShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 2", *NESTED[1:], "---",
        "# Response", "bool bool_value # Comment - Nesting Level 3: 2 of 2"], got)  # fmt: skip
    got = interface(env, *show, f"{PKG}/action/ShortVariedMultiNested")
    c.check("test_show_action", got.stdout.splitlines() == [
        "# Goal definition", "ShortVariedNested short_varied_nested # Comment - Nesting Level 3: 1 of 2", *NESTED[1:],
        "---", "# Result definition", "bool bool_value # Comment - Nesting Level 3: 2 of 2", "---",
        "# Feedback definition", "bool[3] bool_values"], got)  # fmt: skip
    got = interface(env, "show", "not_a_package/msg/String")
    c.check(
        "test_show_not_a_package",
        got.returncode == 1 and "Unknown package 'not_a_package'" in got.stderr,
        got,
    )
    got = interface(env, "show", "test_msgs/msg/NotAMessageTypeName")
    c.check("test_show_not_an_interface", got.returncode == 1
            and "Interface 'msg/NotAMessageTypeName' not found in package 'test_msgs'" in got.stderr, got)  # fmt: skip
    got = interface(env, "show", "-", stdin="test_msgs/msg/BasicTypes\n")
    c.check("test_show_stdin", got.stdout.splitlines() == [
        "bool bool_value", "byte byte_value", "char char_value", "float32 float32_value", "float64 float64_value",
        "int8 int8_value", "uint8 uint8_value", "int16 int16_value", "uint16 uint16_value", "int32 int32_value",
        "uint32 uint32_value", "int64 int64_value", "uint64 uint64_value"], got)  # fmt: skip
    got = interface(env, "proto", "geometry_msgs/msg/Point")
    c.check("ros2 interface proto (quoted YAML)", got.stdout == '"x: 0.0\ny: 0.0\nz: 0.0\n"\n', got)
    got = interface(env, "proto", "--no-quotes", "geometry_msgs/msg/Point")
    c.check("ros2 interface proto --no-quotes", got.stdout == "x: 0.0\ny: 0.0\nz: 0.0\n\n", got)
    c.done()
