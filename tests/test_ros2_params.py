"""ROS 2 `param` verbs (list, get, set, describe, delete, dump, load) against the demo node of
tests/test_ros2_services.py: every value asserted is what the node itself stores and reports back."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from tests.support import rostool
from tests.test_ros2_graph import ros2_env
from tests.test_ros2_services import demo_node

DEMO_DUMP = """\
/demo:
  ros__parameters:
    limits:
      max_speed: 3.0
      min_speed: 0.5
    robot_name: r2
    speed: 1.5
    tags:
    - a
    - b
    use_sim_time: false
    wheels: 4
"""
READ_ONLY_WHEELS = "parameter 'wheels' cannot be set because it is read-only"


@pytest.fixture
def demo() -> Iterator[dict[str, str]]:
    with demo_node() as env:
        yield env


def one_error_line(result: subprocess.CompletedProcess[str], expected: str) -> None:
    """A refusal: exit 1, nothing on stdout, one `rostool: ...` line on stderr holding `expected`."""
    assert result.returncode == 1, result
    assert result.stdout == "", result
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rostool: ") and expected in lines[0], lines


def test_param_list_get_set_describe(demo: dict[str, str]) -> None:
    names = ["limits.max_speed", "limits.min_speed", "robot_name", "speed", "tags", "use_sim_time", "wheels"]
    listed = rostool(["param", "list", "/demo"], demo)
    assert listed.stdout.splitlines() == [f"  {n}" for n in names], listed.stderr
    assert rostool(["param", "get", "/demo", "speed"], demo).stdout == "Double value is: 1.5\n"
    assert rostool(["param", "get", "/demo", "robot_name"], demo).stdout == "String value is: r2\n"
    assert json.loads(rostool(["param", "get", "/demo", "tags", "--json"], demo).stdout) == ["a", "b"]

    changed = rostool(["param", "set", "/demo", "speed", "2.25"], demo)
    assert changed.stdout == "Set parameter successful\n", changed.stderr
    changed_back = rostool(["param", "get", "/demo", "speed"], demo)
    assert changed_back.stdout == "Double value is: 2.25\n", changed_back.stderr
    refused = rostool(["param", "set", "/demo", "wheels", "6"], demo)
    one_error_line(refused, f"Setting parameter failed: {READ_ONLY_WHEELS}")  # ros2 param set's words
    missing = rostool(["param", "get", "/demo", "nope"], demo)
    assert missing.returncode == 0 and missing.stdout == "Parameter not set.\n", missing  # undeclared allowed

    described = rostool(["param", "describe", "/demo", "wheels"], demo).stdout
    assert described.splitlines() == [
        "Parameter name: wheels", "  Type: integer", "  Description: the wheels", "  Constraints:",
        "    Read only: true",
    ]  # fmt: skip
    everything = json.loads(rostool(["param", "list", "--json"], demo).stdout)
    assert everything == {"/demo": names}


def test_param_errors(demo: dict[str, str]) -> None:
    every_node = rostool(["param", "get", "speed"], demo)  # newer ros2 param get: PARAM on every node
    assert every_node.stdout == "/demo:\n  Double value is: 1.5\n", every_node
    absent = rostool(["param", "list", "/ghost"], demo)
    one_error_line(absent, "Node not found: /ghost")
    wrong = rostool(["param", "set", "/demo", "tags", "[]"], demo)
    one_error_line(wrong, "cannot be a ROS 2 parameter")


def test_param_delete(demo: dict[str, str]) -> None:
    deleted = rostool(["param", "delete", "/demo", "speed"], demo)
    assert deleted.returncode == 0 and deleted.stdout == "Deleted parameter successfully\n", deleted.stderr
    unset = rostool(["param", "get", "/demo", "speed"], demo)
    assert unset.returncode == 0 and unset.stdout == "Parameter not set.\n", unset  # as ros2 param get
    left = json.loads(rostool(["param", "list", "/demo", "--json"], demo).stdout)
    assert left == ["limits.max_speed", "limits.min_speed", "robot_name", "tags", "use_sim_time", "wheels"]

    refused = rostool(["param", "delete", "/demo", "wheels"], demo)
    one_error_line(refused, f"Deleting parameter failed: {READ_ONLY_WHEELS}")
    assert rostool(["param", "get", "/demo", "wheels"], demo).stdout == "Integer value is: 4\n"

    one_error_line(
        rostool(["param", "delete", "speed"], demo),
        "ROS 2 parameters belong to a node: rostool param delete NODE PARAM",
    )
    one_error_line(rostool(["param", "delete", "/ghost", "speed"], demo), "Node not found: /ghost")


def test_param_dump_edit_load_round_trip(demo: dict[str, str], tmp_path: Path) -> None:
    printed = rostool(["param", "dump", "/demo"], demo)
    assert printed.stdout == DEMO_DUMP + "\n", printed.stderr  # ros2 param dump's trailing blank line
    as_json = json.loads(rostool(["param", "dump", "demo", "--json"], demo).stdout)
    assert as_json == yaml.safe_load(DEMO_DUMP)

    written = tmp_path / "demo.yaml"
    assert rostool(["param", "dump", "/demo", str(written)], demo).returncode == 0
    assert written.read_text() == DEMO_DUMP
    document = yaml.safe_load(written.read_text())
    section = document["/demo"]["ros__parameters"]
    section["limits"]["max_speed"] = 4.5
    section["robot_name"] = "42"  # a string that looks like a number stays a string
    section["speed"] = 0.75
    section["tags"] = []  # typed by the node's current string array
    written.write_text(yaml.safe_dump(document))

    loaded = rostool(["param", "load", "/demo", str(written)], demo)
    assert loaded.stdout.splitlines() == [
        "Set parameter limits.max_speed successful", "Set parameter limits.min_speed successful",
        "Set parameter robot_name successful", "Set parameter speed successful",
        "Set parameter tags successful", "Set parameter use_sim_time successful",
    ], loaded.stderr  # fmt: skip
    # as ros2 param load: every parameter judged on its own, the read-only one refused
    assert loaded.stderr == f"Set parameter wheels failed: {READ_ONLY_WHEELS}\n"
    assert loaded.returncode == 1

    assert yaml.safe_load(rostool(["param", "dump", "/demo"], demo).stdout) == document
    assert rostool(["param", "get", "/demo", "robot_name"], demo).stdout == "String value is: 42\n"
    tags = rostool(["param", "describe", "/demo", "tags", "--json"], demo).stdout
    assert json.loads(tags)[0]["type"] == "string array"


def test_param_load_wildcard_and_node_sections(demo: dict[str, str], tmp_path: Path) -> None:
    both = tmp_path / "both.yaml"
    both.write_text(
        "/**:\n  ros__parameters:\n    speed: 9.5\n    use_sim_time: true\n"
        "demo:\n  ros__parameters:\n    speed: 2.0\n    limits: {min_speed: 0.25}\n"
    )
    loaded = rostool(["param", "load", "/demo", str(both)], demo)
    assert loaded.returncode == 0, loaded.stderr
    assert loaded.stdout.splitlines() == [
        "Set parameter speed successful", "Set parameter use_sim_time successful",
        "Set parameter limits.min_speed successful",
    ]  # fmt: skip
    now = json.loads(rostool(["param", "dump", "/demo", "--json"], demo).stdout)["/demo"]["ros__parameters"]
    assert now["speed"] == 2.0  # the node's own section wins over /**
    assert now["use_sim_time"] is True
    assert now["limits"] == {"max_speed": 3.0, "min_speed": 0.25}

    skipping = rostool(["param", "load", "/demo", str(both), "--no-use-wildcard"], demo)
    assert skipping.stdout == "Set parameter speed successful\nSet parameter limits.min_speed successful\n"

    only_wildcard = tmp_path / "wildcard.yaml"
    only_wildcard.write_text("/**:\n  ros__parameters:\n    robot_name: everyone\n")
    refused = rostool(["param", "load", "/demo", str(only_wildcard), "--no-use-wildcard"], demo)
    one_error_line(
        refused, f"{only_wildcard} does not contain any valid parameters for /demo (/** is skipped"
    )
    assert rostool(["param", "get", "/demo", "robot_name"], demo).stdout == "String value is: r2\n"
    assert rostool(["param", "load", "/demo", str(only_wildcard)], demo).returncode == 0
    assert rostool(["param", "get", "/demo", "robot_name"], demo).stdout == "String value is: everyone\n"

    from_stdin = rostool(
        ["param", "load", "/demo", "-"], demo, input="/demo:\n  ros__parameters: {wheels: 4}\n"
    )
    assert from_stdin.stderr == f"Set parameter wheels failed: {READ_ONLY_WHEELS}\n"


def test_param_load_bad_files(demo: dict[str, str], tmp_path: Path) -> None:
    def load(text: str) -> subprocess.CompletedProcess[str]:
        path = tmp_path / "bad.yaml"
        path.write_text(text)
        return rostool(["param", "load", "/demo", str(path)], demo)

    bad = str(tmp_path / "bad.yaml")
    one_error_line(load("/demo: [unclosed\n"), f"invalid YAML in {bad} (line 2")
    one_error_line(load("- just a list\n"), f"{bad} is not a ROS 2 parameter file")
    one_error_line(load("/demo:\n  speed: 3.0\n"), f"{bad} is not a valid ROS parameter file for node /demo")
    one_error_line(
        load("/other:\n  ros__parameters:\n    speed: 3.0\n"),
        f"{bad} does not contain any valid parameters for /demo or /**; its keys: /other",
    )
    one_error_line(
        load("/demo:\n  ros__parameters:\n    speed: 3.0\n    tags: [1, a]\n"),
        f"{bad}: parameter tags: [1, 'a'] cannot be a ROS 2 parameter",
    )
    assert rostool(["param", "get", "/demo", "speed"], demo).stdout == "Double value is: 1.5\n"  # none sent

    one_error_line(rostool(["param", "load", "/demo", str(tmp_path / "absent.yaml")], demo), "cannot read")
    one_error_line(
        rostool(["param", "load", "/demo"], demo),
        "ROS 2 parameters belong to a node: rostool param load NODE FILE",
    )
    one_error_line(rostool(["param", "dump", "/ghost"], demo), "Node not found: /ghost")


@pytest.mark.parametrize("verb", ["delete", "dump", "load"])
def test_param_help_has_examples(verb: str) -> None:
    shown = rostool(["param", verb, "--help"], ros2_env())
    assert shown.returncode == 0 and "Example" in shown.stdout and "--ros2 param" in shown.stdout
