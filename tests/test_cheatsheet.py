"""`rostool cheatsheet`: the corrected, searchable command reference."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from typing import Any

import click
import pytest
import yaml
from click.testing import CliRunner

from rostool.cli import root
from rostool.reference import CheatsheetDataError, Reference, load_reference, search
from rostool.reference.model import build_reference, data_path, live_command_groups
from rostool.reference.search import Column
from rostool.reference.verbs import missing_rostool_verbs, unknown_rostool_flags, unplanned_rostool_verbs
from tests.support import rostool

SECTIONS = ["nodes", "topics", "params", "bags", "services", "actions", "interfaces", "build", "python"]
JSON_KEYS = {
    *("section", "ros1", "ros2", "rostool", "rostool_ros2"),
    *("description", "inputs", "output", "aliases"),
}
RECORD = (
    "rosbag record -o <prefix>",
    "rosbag record -a",
    "rosbag record -O <file.bag>",
    "rosbag record <topic>...",
)
ROSRUN = "rosrun <pkg> <executable>"

# (as printed in the book, acceptable first hits, wrong form named in the note, correction in the note)
BOOK_ERRORS: list[tuple[str, tuple[str, ...], str, str]] = [
    ("roscd list", ("rosnode list",), "roscd list", "rosnode list"),  # E1
    ("roscpp list", ("rosnode list",), "roscpp list", "rosnode list"),  # E2
    ("roscpp info (node_name)", ("rosnode info <node>",), "roscpp info", "rosnode info"),  # E3
    ("roscpp kill (node_name)", ("rosnode kill <node>",), "roscpp kill", "rosnode kill"),  # E4
    ("roscpp ping (node_name)", ("rosnode ping <node>",), "roscpp ping", "rosnode ping"),  # E5
    ("roscpp param get (param)", ("rosparam get <name>",), "roscpp param get", "rosparam get"),  # E6
    ("roscpp param set (param, value)", ("rosparam set <name> <value>",), "roscpp param set", "rosparam set"),
    ("roscpp param delete (param)", ("rosparam delete <name>",), "roscpp param delete", "rosparam delete"),
    ("roscpp run (package, node)", (ROSRUN,), "roscpp run", "rosrun"),  # E9
    ("roscpp core", ("roscore",), "roscpp core", "roscore"),  # E10
    ("roscparam get /roscdistro", ("rosparam get <name>",), "roscparam get", "rosparam get"),  # E11
    ("roscparam set /wheel_radius 0.05", ("rosparam set <name> <value>",), "roscparam set", "rosparam set"),
    ("roscparam get /wheel_radius", ("rosparam get <name>",), "roscparam get", "rosparam get"),
    ("roscfg record -a -o test.bag", RECORD, "roscfg record", "rosbag record"),  # E12
    (
        "roscfg set /threshold_temp 35.0",
        ("rosparam set <name> <value>",),
        "roscfg set",
        "rosparam set",
    ),  # E13
    ("roslaunch play -l test.bag", ("rosbag play -l <file.bag>",), "roslaunch play", "rosbag play"),  # E14
    (
        "roslaunch play -r 2.0 test.bag",
        ("rosbag play -r <factor> <file.bag>",),
        "roslaunch play",
        "rosbag play",
    ),
    ("rosvbag record -a -o <file>", RECORD, "rosvbag record", "rosbag record"),  # E16
    ("rosvbag play <file>", ("rosbag play <file.bag>",), "rosvbag play", "rosbag play"),
    ("rosvbag play -l <file>", ("rosbag play -l <file.bag>",), "rosvbag play", "rosbag play"),
    ("rosvbag play -r <rate> <file>", ("rosbag play -r <factor> <file.bag>",), "rosvbag play", "rosbag play"),
    ("rosvbag info test.bag", ("rosbag info <file.bag>",), "rosvbag info", "rosbag info"),
    (
        "roslaunch <package_name> <executable_file>",  # E17
        (ROSRUN,),
        "roslaunch <package_name> <executable_file>",
        "rosrun <package_name> <executable_file>",
    ),
    (
        "roslaunch ros_pkg publisher_script.py",
        (ROSRUN,),
        "roslaunch ros_pkg publisher_script.py",
        "rosrun ros_pkg publisher_script.py",
    ),
    (
        "roslaunch usb_cam usb_cam_node",
        (ROSRUN,),
        "roslaunch usb_cam usb_cam_node",
        "rosrun usb_cam usb_cam_node",
    ),
    ("roslaunch rviz rviz", ("rosrun rviz rviz",), "roslaunch rviz rviz", "rosrun rviz rviz"),  # E19
    (
        "roslaunch sum_two_numbers server.py",  # E20
        (ROSRUN,),
        "roslaunch sum_two_numbers server.py",
        "rosrun sum_two_numbers server.py",
    ),
    (
        "roslaunch sum_two_numbers client.py",
        (ROSRUN,),
        "roslaunch sum_two_numbers client.py",
        "rosrun sum_two_numbers client.py",
    ),
    (
        "roslaunch robot_navigation_pkg robot_state_publisher.py",  # E21
        (ROSRUN,),
        "roslaunch robot_navigation_pkg robot_state_publisher.py",
        "rosrun robot_navigation_pkg robot_point_pub.py",
    ),
    (
        "roslaunch robot_navigation_pkg action_client.py",
        (ROSRUN,),
        "roslaunch robot_navigation_pkg action_client.py",
        "rosrun robot_navigation_pkg action_client.py",
    ),
    ("rostopic echo /hello.world", ("rostopic echo <topic>",), "/hello.world", "/hello_world"),  # E22
    ("rostopic info /hello.world", ("rostopic info <topic>",), "/hello.world", "/hello_world"),
    ("rostopic hz /hello.world", ("rostopic hz <topic>",), "/hello.world", "/hello_world"),
    ("/hello.world", ("rostopic echo <topic>",), "/hello.world", "/hello_world"),
    ("/hello.world/pub_node", ("rosnode list",), "/hello.world/pub_node", "/hello_world_pub_node"),  # E23
    ("/roscdistro", ("rosparam get <name>",), "/roscdistro", "/rosdistro"),  # E24
    (
        "rospy.Publisher(topic, type, queue.size)",  # E25
        ("rospy.Publisher(topic, data_class, queue_size=10)",),
        "queue.size",
        "queue_size",
    ),
    ("queue.size", ("rospy.Publisher(topic, data_class, queue_size=10)",), "queue.size", "queue_size"),
    (
        "navigate_2D_action",  # E26
        ("actionlib.SimpleActionClient(name, ActionSpec)",),
        "navigate_2D_action",
        "navigate_2d_action",
    ),
    (
        "self.publish_feedback(feedback_msg)",  # E28
        ("server.publish_feedback(feedback)",),
        "self.publish_feedback",
        "self.action_server.publish_feedback",
    ),
]


@pytest.fixture(scope="module")
def reference() -> Reference:
    return load_reference(available_groups=live_command_groups(root))


@pytest.fixture(scope="module")
def raw_data() -> dict[str, Any]:
    loaded: dict[str, Any] = yaml.safe_load(data_path().read_text(encoding="utf-8"))
    return loaded


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return rostool(["cheatsheet", *args], env=dict(os.environ))


def invoke(*args: str) -> Any:
    return CliRunner().invoke(root, ["cheatsheet", *args], env={"COLUMNS": "200"})


def test_every_section_is_present_and_printed(reference: Reference) -> None:
    assert list(reference.section_ids) == SECTIONS
    assert all(section.entries for section in reference.sections)
    done = run()
    assert done.returncode == 0, done.stderr
    for section in reference.sections:
        assert f"{section.title}\n{'=' * len(section.title)}" in done.stdout
    for command in ("catkin_make", "catkin_create_pkg", "rosrun", "roslaunch", "roscd", "rospack list-names"):
        assert f"\n{command}" in done.stdout
    for function in ("rospy.init_node(", "rospy.Rate(", "actionlib.SimpleActionServer(", "Vector3(x, y, z)"):
        assert f"\n{function}" in done.stdout


def test_book_commands_and_common_flags_are_covered(reference: Reference) -> None:
    forms = {entry.ros1 for entry in reference.iter_entries()}
    expected = {
        "roscore",
        "rosnode list",
        "rosnode info <node>",
        "rosnode kill <node>",
        "rosnode ping <node>",
        "rostopic list",
        "rostopic echo <topic>",
        "rostopic echo -n <count> <topic>",
        "rostopic info <topic>",
        "rostopic hz <topic>",
        "rostopic bw <topic>",
        "rostopic type <topic>",
        "rostopic find <type>",
        "rostopic pub -r <hz> <topic> <type> <data>",
        "rostopic pub -1 <topic> <type> <data>",
        "rosparam list",
        "rosparam get <name>",
        "rosparam set <name> <value>",
        "rosparam delete <name>",
        "rosparam dump <file.yaml>",
        "rosparam load <file.yaml>",
        "rosbag record -a",
        "rosbag record -O <file.bag>",
        "rosbag record -o <prefix>",
        "rosbag info <file.bag>",
        "rosbag play -l <file.bag>",
        "rosbag play -r <factor> <file.bag>",
        "rosbag play -s <seconds> <file.bag>",
        "rosbag play -u <seconds> <file.bag>",
        "rosbag play --clock <file.bag>",
        "rosservice list",
        "rosservice type <service>",
        "rosservice call <service> <args>",
        "rosservice info <service>",
        "rossrv show <type>",
        "rosmsg show <type>",
        "rosmsg list",
        "rosrun actionlib_tools axclient.py <action>",
        "rostopic pub <action>/goal <type>ActionGoal <goal>",
        "Ctrl+C",
        "source devel/setup.bash",
        "rospy.is_shutdown()",
        "pub.publish(msg)",
        "rate.sleep()",
        "rospy.spin()",
        "rospy.get_time()",
        "rospy.loginfo(msg)",
        "rospy.logwarn(msg)",
        "rospy.logerr(msg)",
        "rospy.get_param(name, default)",
        "rospy.set_param(name, value)",
        "rospy.ServiceProxy(name, service_class)",
        "client.send_goal(goal, feedback_cb=None)",
        "server.set_succeeded(result)",
        "server.is_preempt_requested()",
        "client.get_result()",
        "LaserScan()",
    }
    assert expected <= forms, sorted(expected - forms)


def test_rosbag_record_o_is_a_prefix_and_capital_o_the_exact_name(reference: Reference) -> None:
    prefix = reference.entry("rosbag record -o <prefix>")
    exact = reference.entry("rosbag record -O <file.bag>")
    assert prefix is not None and exact is not None
    assert "prefix" in prefix.description and "test_YYYY-MM-DD-HH-MM-SS.bag" in prefix.description
    assert "exactly" in exact.description


@pytest.mark.parametrize(
    ("printed", "firsts", "wrong", "right"), BOOK_ERRORS, ids=[c[0] for c in BOOK_ERRORS]
)
def test_book_misspelling_resolves_to_the_right_command_first(
    reference: Reference, printed: str, firsts: tuple[str, ...], wrong: str, right: str
) -> None:
    result = search(reference, printed)
    assert result.hits, printed
    assert result.hits[0].entry.ros1 in firsts, [hit.entry.ros1 for hit in result.hits[:3]]
    assert any(
        note.startswith(f"note: '{wrong}' is ") and " in the book; the " in note and f" is '{right}'" in note
        for note in result.notes
    ), result.notes


def test_roscpp_list_on_the_command_line_shows_rosnode_list_and_the_note() -> None:
    done = run("roscpp list")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "note: 'roscpp list' is a misspelling in the book; the command is 'rosnode list'"
    assert lines[2].startswith("rosnode list")
    assert "ros2 node list" in done.stdout

    as_json = run("roscpp", "list", "--format", "json")
    assert json.loads(as_json.stdout)[0]["ros1"] == "rosnode list"
    assert "note: 'roscpp list' is a misspelling in the book" in as_json.stderr


def test_every_entry_ranks_first_for_its_own_exact_form(reference: Reference) -> None:
    for entry in reference.iter_entries():
        first = search(reference, entry.ros1).hits[0].entry
        assert first == entry, f"{entry.ros1!r} found {first.ros1!r} first"


@pytest.mark.parametrize(
    ("query", "first"),
    [
        ("rostopic echo", "rostopic echo <topic>"),
        ("rosbag play", "rosbag play <file.bag>"),
        ("rosbag play -l", "rosbag play -l <file.bag>"),
        ("rostopic pub -1", "rostopic pub -1 <topic> <type> <data>"),
        ("rosparam get /rosdistro", "rosparam get <name>"),
        ("rosservice call /sum_two_ints 7 8", "rosservice call <service> <args>"),
        ("rossrv show sum_two_numbers/SumTwoInts", "rossrv show <type>"),
        ("rosrun robot_navigation_pkg action_server.py", ROSRUN),
        ("roslaunch usb_cam usb_cam-test.launch", "roslaunch <pkg> <file.launch>"),
    ],
)
def test_exact_command_ranks_first(reference: Reference, query: str, first: str) -> None:
    result = search(reference, query)
    assert result.hits[0].entry.ros1 == first
    assert result.notes == ()


@pytest.mark.parametrize(
    ("query", "first"),
    [
        ("rostpic echo", "rostopic echo <topic>"),
        ("rosnode lst", "rosnode list"),
        ("rosbg info", "rosbag info <file.bag>"),
        ("rospy.spn", "rospy.spin()"),
    ],
)
def test_typos_are_tolerated(reference: Reference, query: str, first: str) -> None:
    assert search(reference, query).hits[0].entry.ros1 == first


def test_loop_finds_rosbag_play_l() -> None:
    done = run("loop", "--format", "json")
    assert done.returncode == 0, done.stderr
    first = json.loads(done.stdout)[0]
    assert first["ros1"] == "rosbag play -l <file.bag>"
    assert first["ros2"] == "ros2 bag play -l <bag>"


def test_unquoted_flags_stay_in_the_query() -> None:
    result = invoke("rosbag", "play", "-l", "--format", "json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)[0]["ros1"] == "rosbag play -l <file.bag>"


def test_rospy_rate_finds_the_function(reference: Reference) -> None:
    assert search(reference, "rospy.Rate").hits[0].entry.ros1 == "rospy.Rate(hz)"
    result = invoke("rospy.Rate", "--format", "json")
    assert result.exit_code == 0, result.output
    first = json.loads(result.stdout)[0]
    assert (first["ros1"], first["section"]) == ("rospy.Rate(hz)", "python")


def test_actionlib_methods_are_found(reference: Reference) -> None:
    assert search(reference, "send_goal").hits[0].entry.ros1 == "client.send_goal(goal, feedback_cb=None)"
    assert search(reference, "publish_feedback").hits[0].entry.ros1 == "server.publish_feedback(feedback)"
    assert search(reference, "Vector3(1, 2, 3)").hits[0].entry.ros1 == "Vector3(x, y, z)"


def test_json_schema(reference: Reference) -> None:
    done = run("--format", "json")
    assert done.returncode == 0, done.stderr
    items = json.loads(done.stdout)
    assert len(items) == len(reference.entries)
    for item in items:
        assert set(item) == JSON_KEYS
        for key in ("section", "ros1", "description", "inputs", "output"):
            assert isinstance(item[key], str) and item[key]
        assert item["ros2"] is None or isinstance(item["ros2"], str)
        assert item["rostool"] is None or item["rostool"].startswith("rostool ")
        assert item["rostool_ros2"] is None or item["rostool_ros2"].startswith("rostool --ros2 ")
        assert isinstance(item["aliases"], list) and all(isinstance(alias, str) for alias in item["aliases"])
        assert item["section"] in SECTIONS
    by_ros1 = {item["ros1"]: item for item in items}
    assert "roscpp list" in by_ros1["rosnode list"]["aliases"]
    assert "rosvbag info" in by_ros1["rosbag info <file.bag>"]["aliases"]
    assert by_ros1["rosparam get <name>"]["rostool_ros2"] == "rostool --ros2 param get <node> <name>"
    assert by_ros1["rosnode list"]["rostool_ros2"] is None


def test_section_filter() -> None:
    result = invoke("--section", "bags", "--format", "json")
    assert result.exit_code == 0, result.output
    items = json.loads(result.stdout)
    assert items and {item["section"] for item in items} == {"bags"}
    assert "rosbag play -l <file.bag>" in {item["ros1"] for item in items}

    narrowed = invoke("--section", "python", "--format", "json", "publish")
    assert {item["section"] for item in json.loads(narrowed.stdout)} == {"python"}

    text = invoke("--section", "params")
    assert text.stdout.startswith("Parameters\n==========\n")
    assert "rostopic" not in text.stdout


def test_unknown_section_is_one_line_listing_the_valid_ones() -> None:
    done = run("--section", "bogus")
    assert done.returncode != 0
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert "unknown section 'bogus'" in done.stderr
    assert all(section in done.stderr for section in SECTIONS)


def test_no_match_exits_1_with_a_message() -> None:
    done = run("qwxzvbnm")
    assert done.returncode == 1
    assert done.stdout == ""
    assert done.stderr.strip() == (
        "rostool: no cheatsheet entry matches 'qwxzvbnm'; try fewer words, or run 'rostool cheatsheet'"
    )


def test_ros2_reverse_lookup(reference: Reference) -> None:
    done = run("--ros2", "ros2 topic hz", "--format", "json")
    assert done.returncode == 0, done.stderr
    first = json.loads(done.stdout)[0]
    assert first["ros1"] == "rostopic hz <topic>"
    assert first["ros2"] == "ros2 topic hz <topic>"
    entry = reference.entry("rostopic hz <topic>")
    assert entry is not None and first["rostool"] == entry.rostool

    text = run("--ros2", "ros2 topic hz")
    lines = text.stdout.splitlines()
    assert lines[0].startswith("ros2 topic hz <topic>")
    assert "    ROS 1:   rostopic hz <topic>" in lines
    assert any(line.startswith("    rostool: ") for line in lines)

    for query, ros1 in [
        ("ros2 bag play -l", "rosbag play -l <file.bag>"),
        ("ros2 node list", "rosnode list"),
        ("ros2 interface show", "rosmsg show <type>"),
        ("create_subscription", "rospy.Subscriber(topic, data_class, callback)"),
        ("colcon build", "catkin_make"),
    ]:
        assert search(reference, query, column="ros2").hits[0].entry.ros1 == ros1, query


def test_piped_output_has_no_ansi_escapes() -> None:
    env = {
        k: v for k, v in os.environ.items() if k not in ("FORCE_COLOR", "TTY_COMPATIBLE", "TTY_INTERACTIVE")
    }
    env["TERM"] = "xterm-256color"
    for args in ([], ["rosbag play"], ["--section", "python"]):
        done = rostool(["cheatsheet", *args], env=env)
        assert done.returncode == 0, done.stderr
        assert "\x1b" not in done.stdout and done.stdout.strip()


def test_table_and_markdown_formats() -> None:
    table = invoke("rostopic hz", "--format", "table")
    assert table.exit_code == 0, table.output
    assert "rostopic hz <topic>" in table.stdout and "ros2 topic hz <topic>" in table.stdout

    markdown = invoke("--section", "services", "--format", "markdown")
    lines = markdown.stdout.splitlines()
    assert lines[0] == "## Services"
    assert lines[2] == "| ROS 1 | ROS 2 | rostool | Description | Inputs | Output | Aliases |"
    assert any(line.startswith("| `rosservice call <service> <args>` |") for line in lines)


def test_help_has_an_example() -> None:
    result = invoke("--help")
    assert result.exit_code == 0
    assert "Examples:" in result.stdout and "rostool cheatsheet roscpp list" in result.stdout


def test_rich_is_imported_only_for_tables() -> None:
    code = (
        "import sys\n"
        "from click.testing import CliRunner\n"
        "from rostool.cli import root\n"
        "result = CliRunner().invoke(root, ['cheatsheet', 'roscpp list'])\n"
        "assert result.exit_code == 0, result.output\n"
        "print('rich' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=dict(os.environ))
    assert done.stdout.strip() == "False", done.stderr


# --- the data file ------------------------------------------------------------------------------


def test_yaml_validates(reference: Reference, raw_data: dict[str, Any]) -> None:
    entries = [entry for section in raw_data["sections"] for entry in section["entries"]]
    for entry in entries:
        assert {"ros1", "description", "inputs", "output", "ros2", "rostool"} <= set(entry), entry
    ros1_forms = [entry["ros1"] for entry in entries]
    assert len(ros1_forms) == len(set(ros1_forms))
    assert len(reference.entries) == len(entries)


def test_every_alias_leads_to_its_entry(reference: Reference, raw_data: dict[str, Any]) -> None:
    ros1_forms = {entry.ros1 for entry in reference.iter_entries()}
    for misspelling in raw_data["misspellings"]:
        assert misspelling["entry"] in ros1_forms, misspelling
    for entry in reference.iter_entries():
        for alias in entry.all_aliases:
            if alias.startswith("roslaunch <pkg>"):
                continue  # the generic pattern form is exercised by the BOOK_ERRORS cases
            assert search(reference, alias).hits[0].entry == entry, alias


def _broken(raw_data: dict[str, Any]) -> dict[str, Any]:
    return copy.deepcopy(raw_data)


def test_yaml_missing_key_is_rejected(raw_data: dict[str, Any]) -> None:
    data = _broken(raw_data)
    del data["sections"][0]["entries"][0]["output"]
    with pytest.raises(CheatsheetDataError, match="missing output"):
        build_reference(data, available_groups=())


def test_yaml_duplicate_ros1_is_rejected(raw_data: dict[str, Any]) -> None:
    data = _broken(raw_data)
    data["sections"][1]["entries"].append(copy.deepcopy(data["sections"][0]["entries"][0]))
    with pytest.raises(CheatsheetDataError, match="duplicate ros1 form 'roscore'"):
        build_reference(data, available_groups=())


def test_yaml_alias_to_nowhere_or_shared_is_rejected(raw_data: dict[str, Any]) -> None:
    data = _broken(raw_data)
    data["misspellings"][0]["entry"] = "rosnode lisst"
    with pytest.raises(CheatsheetDataError, match="points at unknown entry 'rosnode lisst'"):
        build_reference(data, available_groups=())

    data = _broken(raw_data)
    data["sections"][0]["entries"][1]["aliases"] = ["rosmaster --core"]
    with pytest.raises(CheatsheetDataError, match="belongs to both"):
        build_reference(data, available_groups=())


# --- rostool verbs --------------------------------------------------------------------------------


def test_no_entry_references_a_missing_rostool_verb(reference: Reference) -> None:
    # Command groups land one at a time while this reference names every planned verb. The loader hides
    # (sets to None) a rostool form whose top-level group has no importable module in rostool.cli.COMMANDS
    # yet; for every group that does exist the check is strict: each subcommand named must resolve in the
    # live click tree. Words after the resolved verb are arguments and flags.
    assert missing_rostool_verbs(reference, root) == []
    shown = {entry.rostool.split()[1] for entry in reference.iter_entries() if entry.rostool}
    assert shown <= live_command_groups(root)


def test_flags_in_rostool_forms_exist_on_the_verbs_that_have_landed(reference: Reference) -> None:
    assert unknown_rostool_flags(reference, root) == []


def test_rostool_forms_name_planned_verbs(reference: Reference) -> None:
    assert unplanned_rostool_verbs(reference) == []
    planned = {entry.planned_rostool for entry in reference.iter_entries()}
    assert {"rostool core", "rostool node list", "rostool bag play -l <file.bag>"} <= planned


def test_unbuilt_groups_are_hidden_and_built_ones_checked_strictly() -> None:
    only_topic = load_reference(available_groups={"topic"})
    node_list = only_topic.entry("rosnode list")
    topic_hz = only_topic.entry("rostopic hz <topic>")
    assert node_list is not None and node_list.rostool is None
    assert node_list.planned_rostool == "rostool node list"
    assert topic_hz is not None and topic_hz.rostool == "rostool topic hz <topic>"

    @click.group()
    def fake_root() -> None: ...

    @fake_root.group("topic")
    def fake_topic() -> None: ...

    @fake_topic.command("list")
    def fake_list() -> None: ...

    problems = missing_rostool_verbs(only_topic, root=fake_root)
    assert "rostopic hz <topic>: 'rostool topic' has no subcommand 'hz'" in problems
    assert not any(problem.startswith("rostopic list:") for problem in problems)


# --- rostool's ROS 2 forms ------------------------------------------------------------------------

ROS2_FORMS = {
    "rosparam list": "rostool --ros2 param list <node>",
    "rosparam get <name>": "rostool --ros2 param get <node> <name>",
    "rosparam set <name> <value>": "rostool --ros2 param set <node> <name> <value>",
    "rosparam delete <name>": "rostool --ros2 param delete <node> <name>",
    "rosparam dump <file.yaml>": "rostool --ros2 param dump <node>",
    "rosparam load <file.yaml>": "rostool --ros2 param load <node> <file.yaml>",
    "rosservice call <service> <args>": "rostool --ros2 service call <service> <type> <request>",
    "rosservice info <service>": "rostool --ros2 service info <service>",
    "rostopic info <action>/goal": "rostool --ros2 action info <action>",
    "rostopic pub <action>/goal <type>ActionGoal <goal>": (
        "rostool --ros2 action send-goal --feedback <action> <type> <goal>"
    ),
    "rosbag record -O <file.bag>": "rostool --ros2 bag record -a -o <name>",
    "rosbag play --clock <file.bag>": "rostool --ros2 bag play --clock <bag>",
    "rostopic echo <topic>": "rostool --ros2 topic echo <topic> --qos-reliability best_effort",
}


def test_ros2_forms_are_filled_where_rostool_differs_on_ros2(reference: Reference) -> None:
    for ros1, form in ROS2_FORMS.items():
        entry = reference.entry(ros1)
        assert entry is not None and entry.rostool_ros2 == form, ros1
    for entry in reference.iter_entries():
        if entry.rostool_ros2 is not None:
            assert entry.ros2 is not None, entry.ros1
            assert entry.rostool_ros2 != entry.rostool


def test_text_shows_the_ros2_form_under_the_rostool_form() -> None:
    lines = invoke("rosparam get", "--format", "text").stdout.splitlines()
    at = lines.index("    rostool: rostool param get <name>")
    assert lines[at + 1] == "             rostool --ros2 param get <node> <name>"

    plain_only = invoke("rosnode list", "--format", "text").stdout.splitlines()
    assert "    rostool: rostool node list" in plain_only
    assert not any("--ros2" in line for line in plain_only)


def test_ros2_lookup_puts_the_ros2_form_first() -> None:
    done = run("--ros2", "ros2 param get")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("ros2 param get <node> <name>")
    rostool_line = lines.index("    rostool: rostool --ros2 param get <node> <name>")
    assert lines[rostool_line + 1] == "             rostool param get <name>"
    assert rostool_line < lines.index("    ROS 1:   rosparam get <name>")

    as_json = run("--ros2", "ros2 service call", "--format", "json")
    first = json.loads(as_json.stdout)[0]
    assert first["ros1"] == "rosservice call <service> <args>"
    assert first["rostool_ros2"] == "rostool --ros2 service call <service> <type> <request>"

    table = invoke("--ros2", "ros2 param get", "--format", "table")
    assert table.exit_code == 0, table.output
    ros2_form = table.stdout.index("rostool --ros2 param get <node> <name>")
    assert ros2_form < table.stdout.index("rostool param get <name>")


def test_markdown_shows_both_rostool_forms_in_one_cell() -> None:
    lines = invoke("--section", "params", "--format", "markdown").stdout.splitlines()
    assert lines[2] == "| ROS 1 | ROS 2 | rostool | Description | Inputs | Output | Aliases |"
    assert any(
        line.startswith(
            "| `rosparam get <name>` | `ros2 param get <node> <name>` | "
            "`rostool param get <name>`<br>`rostool --ros2 param get <node> <name>` |"
        )
        for line in lines
    )


def test_ros2_forms_are_searchable(reference: Reference) -> None:
    columns: tuple[Column, ...] = ("ros1", "ros2")
    for column in columns:
        hits = search(reference, "rostool --ros2 param set <node> <name> <value>", column=column).hits
        assert hits[0].entry.ros1 == "rosparam set <name> <value>", column
    assert search(reference, "rostool --ros2 service info", column="ros1").hits[0].entry.ros1 == (
        "rosservice info <service>"
    )


def _with_ros2_form(raw_data: dict[str, Any], ros1: str, form: str) -> dict[str, Any]:
    data = _broken(raw_data)
    for section in data["sections"]:
        for entry in section["entries"]:
            if entry["ros1"] == ros1:
                entry["rostool_ros2"] = form
    return data


def test_yaml_ros2_form_must_start_with_rostool_ros2(raw_data: dict[str, Any]) -> None:
    for form in ("rostool param get <node> <name>", "ros2 param get <node> <name>", "rostool --ros2"):
        data = _with_ros2_form(raw_data, "rosparam get <name>", form)
        with pytest.raises(CheatsheetDataError, match="must start with 'rostool --ros2 <verb>'"):
            build_reference(data, available_groups=())


def test_ros2_form_with_a_missing_flag_or_verb_is_rejected(raw_data: dict[str, Any]) -> None:
    groups = live_command_groups(root)
    bad_flag = "rostool --ros2 topic echo <topic> --qos-reliablity best_effort"
    data = _with_ros2_form(raw_data, "rostopic echo <topic>", bad_flag)
    assert unknown_rostool_flags(build_reference(data, groups), root) == [
        f"rostopic echo <topic>: '{bad_flag}' uses --qos-reliablity, which echo lacks"
    ]

    data = _with_ros2_form(raw_data, "rosparam get <name>", "rostool --ros2 param fetch <node> <name>")
    assert missing_rostool_verbs(build_reference(data, groups), root) == [
        "rosparam get <name>: 'rostool --ros2 param' has no subcommand 'fetch'"
    ]
    assert unplanned_rostool_verbs(build_reference(data, available_groups=())) == [
        "rosparam get <name>: no planned verb 'rostool param fetch'"
    ]

    data = _with_ros2_form(raw_data, "rosnode list", "rostool --ros2 node --all list")
    assert missing_rostool_verbs(build_reference(data, groups), root) == [
        "rosnode list: 'rostool --ros2 node' has no option --all"
    ]


def test_the_root_ros2_option_is_checked_against_the_tree(reference: Reference) -> None:
    @click.group()
    def without_ros2() -> None: ...

    @click.group()
    @click.option("--ros2", is_flag=True)
    def with_ros2(ros2: bool) -> None: ...

    for fake in (without_ros2, with_ros2):

        @fake.group("param")
        def fake_param() -> None: ...

        @fake_param.command("get")
        @click.argument("names", nargs=-1)
        def fake_get(names: tuple[str, ...]) -> None: ...

    only_param = Reference(tuple(s for s in reference.sections if s.id == "params"))
    missing = missing_rostool_verbs(only_param, root=without_ros2)
    assert "rosparam get <name>: 'rostool' has no option --ros2" in missing
    missing = missing_rostool_verbs(only_param, root=with_ros2)
    assert not any(problem.startswith("rosparam get <name>:") for problem in missing)
    assert "rosparam set <name> <value>: 'rostool --ros2 param' has no subcommand 'set'" in missing


def test_unbuilt_groups_hide_the_ros2_form_too() -> None:
    only_topic = load_reference(available_groups={"topic"})
    param_get = only_topic.entry("rosparam get <name>")
    topic_echo = only_topic.entry("rostopic echo <topic>")
    assert param_get is not None and param_get.rostool_ros2 is None
    assert param_get.planned_rostool_ros2 == "rostool --ros2 param get <node> <name>"
    assert topic_echo is not None
    assert topic_echo.rostool_ros2 == "rostool --ros2 topic echo <topic> --qos-reliability best_effort"


def test_a_concept_finds_the_cli_form_before_the_python_api(reference: Reference) -> None:
    hits = [hit.entry for hit in search(reference, "feedback").hits]
    first_code = next(i for i, e in enumerate(hits) if e.section == "python")
    assert first_code > 0 and hits[0].section == "actions", [e.ros1 for e in hits]
    assert any("send-goal --feedback" in (e.rostool_ros2 or "") for e in hits[:first_code])
    # the function's own name still finds the function first
    assert search(reference, "publish_feedback").hits[0].entry.ros1 == "server.publish_feedback(feedback)"


def test_interface_rows_use_the_interface_group(reference: Reference) -> None:
    forms = {
        "rosmsg show <type>": "rostool --ros2 interface show <pkg>/msg/<Type>",
        "rossrv show <type>": "rostool --ros2 interface show <pkg>/srv/<Type>",
        "rosmsg list": "rostool --ros2 interface list -m",
        "rossrv list": "rostool --ros2 interface list -s",
        "rosmsg package <pkg>": "rostool --ros2 interface package <pkg>",
    }
    for ros1, ros2_form in forms.items():
        assert reference.entry(ros1).rostool_ros2 == ros2_form, ros1
    hit = search(reference, "ros2 interface package", column="ros2").hits[0].entry
    assert hit.rostool_ros2 == "rostool --ros2 interface package <pkg>"
