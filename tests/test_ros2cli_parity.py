"""rostool's ROS 2 output against the real `ros2` (ros2cli Jazzy): every case runs `ros2 ARGS` and `rostool
--ros2 ARGS` on the DDS and rclpy backends against the same real rclpy Jazzy nodes, and asserts the same
stdout and exit status after normalizing only what is not deterministic in the output itself (counters and
stamps in the data, goal UUIDs, GIDs, line order where ros2 defines none). Error cases: the same exit status
and one line on rostool's stderr.

Where rostool deliberately does better, DELIBERATE says why (README, "Where rostool differs from ros2cli")
and checks what rostool does instead. Every result goes to docs/ros2cli-parity.json, which
tests/parity_table.py renders as docs/ros2cli-parity.md.
"""

from __future__ import annotations

import dataclasses
import json
import re
import select
import subprocess
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import click
import pytest
import yaml

from rostool.cli import root
from tests.parity_ros2cli import (
    BACKENDS,
    DIFFERS,
    MISSING,
    ONLY_ROSTOOL,
    ROS2,
    SAME,
    Case,
    ParityGraph,
    Run,
    daemon_answer,
    digits_zeroed,
    gids,
    goal_accepted_first,
    goal_ids,
    judge,
    parity_graph,
    record,
    require_ros2cli,
    service_wait,
    sorted_lines,
    subscription_wait,
    wait_ros2,
    without_observers,
)
from tests.support import ros2_env, wait_until

# its texts keep one length ('hello 1000'...): two tools' echoes take different messages, and `--no-str`
# prints the length (seen in CI: 'hello 99' and 'hello 100' taken by ros2 and rostool)
TALKER = ["--name", "parity_talker", "--talk", "/chatter", "--first", "1000", "--rate", "5",
          "--stamped", "/stamped"]  # fmt: skip
HIDER = ["--name", "_parity_hider", "--talk", "/_parity_hidden", "--rate", "2"]  # a hidden node and topic
SERVER = ["--name", "parity_server", "--params", "--service", "/set_flag", "--action", "/fibonacci",
          "--step", "0.05", "--listen", "/chatter", "--listen", "/parity_pub"]  # fmt: skip


def _ready(graph: ParityGraph) -> bool:
    """ros2's daemon knows every node, topic endpoint, service and action of the module's graph (asked in
    this process, as `ros2 node list -a`, `service list`, `action list` and `topic list -v` ask it)."""
    daemon = graph.ros2_daemon
    return (
        {"/parity_server", "/parity_talker", "/_parity_hider"} <= set(daemon.nodes(hidden=True) or ())
        and {"/set_flag", "/parity_server/set_parameters", "/parity_talker/get_parameters"}
        <= daemon.names("get_service_names_and_types")
        and "/fibonacci" in daemon.names("get_action_names_and_types")
        and {"/chatter", "/stamped", "/_parity_hidden"} <= daemon.names("get_topic_names_and_types")
        and daemon.ask("count_subscribers", "/chatter") == 1
    )


@pytest.fixture(scope="module")
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ParityGraph]:
    with parity_graph(tmp_path_factory.mktemp("parity"), [TALKER, SERVER, HIDER], _ready) as made:
        yield made


def case(verb: str, flags: str, *args: str, **options: object) -> Case:
    return Case(verb, flags, tuple(args), **options)  # type: ignore[arg-type]


def listing(verb: str, flags: str, *args: str, **options: object) -> Case:
    return case(verb, flags, *args, graph=True, **options)


# fmt: off
CASES = [
    # --- node --- (-c first: ros2 counts a node of rostool's rclpy backend that it still sees)
    listing("node list", "-c", "node", "list", "-c"),
    listing("node list", "", "node", "list", normalize=without_observers),
    listing("node list", "-a", "node", "list", "-a", normalize=without_observers),
    listing("node info", "", "node", "info", "/parity_talker"),
    listing("node info", "(actions, services)", "node", "info", "/parity_server"),
    listing("node info", "(unknown node)", "node", "info", "/parity_nobody", error=True),
    # --- topic: the graph ---
    listing("topic list", "", "topic", "list"),
    listing("topic list", "-t", "topic", "list", "-t"),
    listing("topic list", "-c", "topic", "list", "-c"),
    listing("topic list", "-v", "topic", "list", "-v"),
    listing("topic list", "--include-hidden-topics", "topic", "list", "--include-hidden-topics"),
    listing("topic info", "", "topic", "info", "/chatter"),
    listing("topic info", "-v", "topic", "info", "-v", "/chatter", normalize=gids),
    listing("topic info", "(unknown topic)", "topic", "info", "/parity_nothing", error=True),
    listing("topic type", "", "topic", "type", "/stamped"),
    listing("topic find", "", "topic", "find", "std_msgs/msg/String"),
    listing("topic find", "-c", "topic", "find", "-c", "geometry_msgs/msg/PointStamped"),
    # --- service ---
    listing("service list", "", "service", "list"),
    listing("service list", "-t", "service", "list", "-t"),
    listing("service list", "-c", "service", "list", "-c"),
    listing("service type", "", "service", "type", "/set_flag"),
    listing("service find", "", "service", "find", "std_srvs/srv/SetBool"),
    listing("service find", "-c", "service", "find", "-c", "rcl_interfaces/srv/GetParameters"),
    case(
        "service call",
        "",
        "service",
        "call",
        "/set_flag",
        "std_srvs/srv/SetBool",
        "{data: true}",
        normalize=service_wait,
    ),
    case("service call", "--stdin", "service", "call", "--stdin", "/set_flag", "std_srvs/srv/SetBool",
         normalize=service_wait, stdin="data: false\n"),
    # --- action ---
    listing("action list", "", "action", "list"),
    listing("action list", "-t", "action", "list", "-t"),
    listing("action list", "-c", "action", "list", "-c"),
    listing("action info", "", "action", "info", "/fibonacci"),
    listing("action info", "-t", "action", "info", "-t", "/fibonacci"),
    listing("action info", "-c", "action", "info", "-c", "/fibonacci"),
    case(
        "action send_goal",
        "",
        "action",
        "send_goal",
        "/fibonacci",
        "test_msgs/action/Fibonacci",
        "{order: 3}",
        normalize=goal_ids,
    ),
    case(
        "action send_goal",
        "--feedback",
        "action",
        "send_goal",
        "--feedback",
        "/fibonacci",
        "test_msgs/action/Fibonacci",
        "{order: 3}",
        normalize=goal_accepted_first,
    ),
    # --- param ---
    case("param list", "NODE", "param", "list", "/parity_server"),
    listing("param list", "", "param", "list", normalize=without_observers),
    *[
        case("param get", f"({kind})", "param", "get", "/parity_server", name)
        for kind, name in (
            ("bool", "flag"),
            ("integer", "count"),
            ("double", "speed"),
            ("string", "label"),
            ("byte array", "blob"),
            ("bool array", "switches"),
            ("integer array", "ids"),
            ("double array", "gains"),
            ("string array", "names"),
        )
    ],
    case("param get", "--hide-type", "param", "get", "--hide-type", "/parity_server", "ids"),
    case("param get", "(unknown parameter)", "param", "get", "/parity_server", "parity_nope", error=True),
    case("param get", "(unknown node)", "param", "get", "/parity_nobody", "count", error=True),
    case("param set", "", "param", "set", "/parity_server", "label", "r2"),
    case("param set", "(wrong type)", "param", "set", "/parity_server", "count", "hello"),
    case("param describe", "", "param", "describe", "/parity_server", "count"),
    case("param delete", "(undeclared)", "param", "delete", "/parity_server", "parity_nope"),
    case("param dump", "", "param", "dump", "/parity_server"),
    # --- interface ---
    case("interface list", "", "interface", "list"),
    case("interface packages", "", "interface", "packages"),
    case("interface package", "", "interface", "package", "std_srvs", normalize=sorted_lines),
    case("interface show", "", "interface", "show", "geometry_msgs/msg/PointStamped"),
    case("interface show", "(action)", "interface", "show", "test_msgs/action/Fibonacci"),
    case("interface show", "--all-comments", "interface", "show", "--all-comments", "std_msgs/msg/Header"),
    case("interface show", "--no-comments", "interface", "show", "--no-comments", "std_srvs/srv/SetBool"),
    case("interface show", "(unknown type)", "interface", "show", "std_msgs/msg/ParityNope", error=True),
    case("interface proto", "", "interface", "proto", "geometry_msgs/msg/PointStamped"),
    case("interface proto", "--no-quotes", "interface", "proto", "--no-quotes", "std_msgs/msg/String"),
    # --- topic: messages ---
    case("topic echo", "--once", "topic", "echo", "--once", "/chatter", normalize=digits_zeroed),
    case("topic echo", "--no-str", "topic", "echo", "--once", "--no-str", "/chatter"),
    case(
        "topic echo",
        "--no-arr",
        "topic",
        "echo",
        "--once",
        "--no-arr",
        "/parameter_events",
        normalize=digits_zeroed,
        poke=("param", "set", "/parity_server", "speed", "0.5"),  # its own value: an event, nothing changed
    ),
    case("topic echo", "--csv", "topic", "echo", "--once", "--csv", "/stamped", normalize=digits_zeroed),
    case(
        "topic echo",
        "--field",
        "topic",
        "echo",
        "--once",
        "--field",
        "point",
        "/stamped",
        normalize=digits_zeroed,
    ),
    case(
        "topic echo",
        "--flow-style",
        "topic",
        "echo",
        "--once",
        "--flow-style",
        "/stamped",
        normalize=digits_zeroed,
    ),
    case("topic echo", "--truncate-length", "topic", "echo", "--once", "--truncate-length", "2", "/chatter"),
    case(
        "topic echo",
        "--qos-reliability",
        "topic",
        "echo",
        "--once",
        "--qos-reliability",
        "best_effort",
        "/chatter",
        normalize=digits_zeroed,
    ),
    case(
        "topic echo",
        "TYPE",
        "topic",
        "echo",
        "--once",
        "/chatter",
        "std_msgs/msg/String",
        normalize=digits_zeroed,
    ),
    case("topic echo", "(unknown topic)", "topic", "echo", "--once", "/parity_missing", error=True),
    case("topic pub", "--once", "topic", "pub", "--once", "/parity_pub", "std_msgs/msg/String", "{data: hi}"),
    case("topic pub", "-w --once", "topic", "pub", "-w", "1", "--once", "/parity_pub", "std_msgs/msg/String",
         "{data: hi}", normalize=subscription_wait),
    case("topic pub", "-w -t -r", "topic", "pub", "-w", "1", "-t", "2", "-r", "20", "/parity_pub",
         "std_msgs/msg/String", "{data: hi}", normalize=subscription_wait),
    case("topic pub", "-1 -w --keep-alive", "topic", "pub", "-1", "-w", "1", "--keep-alive", "0.2",
         "/parity_pub", "std_msgs/msg/String", "{data: hi}", normalize=subscription_wait),
    # --- more flags and errors ---
    listing("topic type", "(unknown topic)", "topic", "type", "/parity_nothing", error=True),
    listing("service type", "(unknown service)", "service", "type", "/parity_nothing", error=True),
    listing("action info", "(unknown action)", "action", "info", "/parity_nothing"),
    listing("node info", "--include-hidden", "node", "info", "--include-hidden", "/parity_server"),
    case("param list", "--filter", "param", "list", "/parity_server", "--filter", "^s"),
    case("param list", "--param-prefixes", "param", "list", "/parity_server", "--param-prefixes", "use"),
    case("param describe", "(several)", "param", "describe", "/parity_server", "count", "label"),
    case("topic pub", "-p", "topic", "pub", "-w", "1", "-t", "3", "-p", "2", "-r", "20", "/parity_pub",
         "std_msgs/msg/String", "{data: hi}", normalize=subscription_wait),
    case("interface proto", "(unknown type)", "interface", "proto", "std_msgs/msg/ParityNope", error=True),
    case("interface package", "(unknown package)", "interface", "package", "parity_nopkg", error=True),
    # --- facts of ros2cli's own tests (ros2topic, ros2service, ros2action test_cli.py) ---
    case("topic echo", "--field (nested)", "topic", "echo", "--once", "--field", "header.stamp", "/stamped",
         normalize=digits_zeroed),
    case("topic echo", "--field (not a member)", "topic", "echo", "--once", "--field", "not_member",
         "/stamped", error=True),
    case("topic echo", "--field (no name)", "topic", "echo", "--once", "--field", ".", "/stamped",
         error=True),
    listing("topic find", "(not a type)", "topic", "find", "not_a_topic_typename"),
    listing("topic type", "(hidden topic)", "topic", "type", "/_parity_hidden", error=True),
    listing("service find", "(not a type)", "service", "find", "not_a_service_typename"),
    case("service call", "(no request)", "service", "call", "/set_flag", "std_srvs/srv/SetBool",
         normalize=service_wait),
    case("action send_goal", "(not a goal field)", "action", "send_goal", "/fibonacci",
         "test_msgs/action/Fibonacci", "{ordr: 3}", error=True),
    # --- facts of ros2node's, ros2service's and ros2action's test_cli.py: hidden nodes and services ---
    listing("node list", "-c -a", "node", "list", "-c", "-a", served=False),
    listing("node info", "(hidden node)", "node", "info", "/_parity_hider", error=True),
    listing("node info", "--include-hidden (hidden node)", "node", "info", "--include-hidden",
            "/_parity_hider"),
    listing("service list", "--include-hidden-services", "service", "list", "--include-hidden-services"),
    listing("service find", "--include-hidden-services", "service", "find", "--include-hidden-services",
            "rcl_interfaces/srv/GetParameters"),
    listing("action type", "", "action", "type", "/fibonacci"),
    listing("service info", "", "service", "info", "/set_flag"),
    listing("service info", "(unknown service)", "service", "info", "/parity_nothing", error=True),
    listing("action type", "(unknown action)", "action", "type", "/parity_nothing", error=True),
    # --- facts of ros2interface's test_cli.py ---
    case("interface package", "-m", "interface", "package", "std_msgs", "-m", normalize=sorted_lines),
    case("interface package", "-s", "interface", "package", "std_srvs", "-s", normalize=sorted_lines),
    case("interface package", "-a (none)", "interface", "package", "std_msgs", "-a"),
    case("interface show", "(unknown package)", "interface", "show", "not_a_package/msg/String", error=True),
    case("interface show", "(service)", "interface", "show", "std_srvs/srv/Empty"),
    case("interface show", "- (stdin)", "interface", "show", "-", stdin="std_srvs/srv/Empty\n"),
    # --- facts of ros2topic's test_echo_pub.py ---
    case("topic pub", "-t --max-wait-time-secs (no subscriber)", "topic", "pub", "-t", "5",
         "--max-wait-time-secs", "1", "/parity_unread", "std_msgs/String", "data: hello", error=True,
         normalize=subscription_wait),
    case("topic pub", "--max-wait-time-secs (alone)", "topic", "pub", "--max-wait-time-secs", "1",
         "/parity_unread", "std_msgs/String", "data: hello", error=True),
    case("topic pub", "-t -w 0", "topic", "pub", "-t", "3", "-w", "0", "-r", "5", "/parity_unread",
         "std_msgs/String", "data: hello"),
    case("topic echo", "--timeout (no publisher)", "topic", "echo", "--timeout", "1", "/parity_silent",
         "std_msgs/msg/String"),
    # --- QoS: history, liveliness, lease ---
    case("topic echo", "--qos-history", "topic", "echo", "--once", "--qos-history", "keep_all", "/chatter",
         normalize=digits_zeroed),
    case("topic echo", "--qos-history --qos-depth", "topic", "echo", "--once", "--qos-history", "keep_last",
         "--qos-depth", "3", "/chatter", normalize=digits_zeroed),
    case("topic echo", "--qos-liveliness", "topic", "echo", "--once", "--qos-liveliness", "automatic",
         "/chatter", normalize=digits_zeroed),
    case("topic echo", "--qos-reliability system_default", "topic", "echo", "--once", "--qos-reliability",
         "system_default", "/chatter", normalize=digits_zeroed),
    case("topic pub", "--qos-history", "topic", "pub", "-w", "1", "--once", "--qos-history", "keep_all",
         "/parity_pub", "std_msgs/msg/String", "{data: hi}", normalize=subscription_wait),
    case("topic pub", "--qos-liveliness --qos-liveliness-lease-duration-seconds", "topic", "pub", "-w", "1",
         "--once", "--qos-liveliness", "manual_by_topic", "--qos-liveliness-lease-duration-seconds", "2",
         "/parity_pub", "std_msgs/msg/String", "{data: hi}", normalize=subscription_wait),
]
# fmt: on


def _no_comments(text: str) -> str:
    """A definition as rostool knows it: no comment lines, no blank lines, no trailing comments."""
    lines = (re.sub(r"\s*#.*$", "", line) for line in text.splitlines())
    return "".join(line + "\n" for line in lines if line.strip())


def _one_error_line(ros2: Run, tool: Run) -> bool:
    return tool.code == 1 and not tool.stdout and len(tool.stderr_lines) == 1


# rostool does better here, on purpose: why (README, "Where rostool differs from ros2cli"), and what it does
Deliberate = tuple[str, Callable[[Run, Run], bool]]
DELIBERATE: dict[str, Deliberate] = {
    "param set /parity_server count hello": (
        "a refused set exits 1 (ros2 exits 0), so scripts see the failure; the line names the node",
        _one_error_line,
    ),
    "action info /parity_nothing": (
        "an action nobody serves prints ros2's zero counts and then exits 1 with one line (ros2 exits 0), so "
        "a script can tell a mistyped name",
        lambda ros2, tool: tool.stdout == ros2.stdout and tool.code == 1 and len(tool.stderr_lines) == 1,
    ),
    "param delete /parity_server parity_nope": (
        "a refused delete exits 1 (ros2 exits 0), so scripts see the failure; the line names the node",
        _one_error_line,
    ),
    "topic echo --once --flow-style /stamped": (
        "Jazzy's ros2 ignores --flow-style for messages (its YAML representer builds block mappings); "
        "rostool prints the flow style asked for",
        lambda ros2, tool: tool.code == 0 and tool.stdout.startswith("{header: {stamp: {sec: "),
    ),
    "topic echo --once /parity_missing": (
        "ros2 gives up at once when no publisher tells the type; rostool waits for one (a publisher "
        "started after the echo is echoed), and its warning goes to stderr, not into the data on stdout",
        lambda ros2, tool: tool.code is None and not tool.stdout,
    ),
    "topic pub --once /parity_pub std_msgs/msg/String {data: hi}": (
        "ros2's --once waits for ever for a first subscriber (-w 1 by default); rostool waits only for the "
        "subscribers discovery shows (a few seconds at most), so it never hangs on a topic nobody reads; "
        "-w N waits as ros2 does",
        lambda ros2, tool: tool.code == 0 and tool.stdout == subscription_wait(ros2.stdout),
    ),
    "topic echo --timeout 1 /parity_silent std_msgs/msg/String": (
        "an echo whose --timeout passed without a message exits 1 with one line saying so (ros2 exits 0 "
        "silently), so a script can tell that nothing arrived",
        lambda ros2, tool: (
            tool.code == 1
            and not tool.stdout
            and tool.stderr_lines[-1:] == ["rostool: no message within 1 s"]
        ),
    ),
    "interface list": (
        "rostool needs no ROS install: it lists the interfaces it carries (rosbags' store of the distro), "
        "not the packages installed beside it",
        lambda ros2, tool: tool.code == 0 and "    std_msgs/msg/String\n" in tool.stdout,
    ),
    "interface packages": (
        "rostool needs no ROS install: it lists the packages it carries, not the ones installed beside it",
        lambda ros2, tool: tool.code == 0 and "std_msgs\n" in tool.stdout,
    ),
    **{
        f"interface show {args}": (
            "rostool's definitions come from rosbags' store, which keeps no comments",
            lambda ros2, tool: tool.stdout == _no_comments(ros2.stdout),
        )
        for args in (
            "geometry_msgs/msg/PointStamped",
            "test_msgs/action/Fibonacci",
            "--all-comments std_msgs/msg/Header",
        )
    },
    "interface show --no-comments std_srvs/srv/SetBool": (
        "ros2 leaves each comment's '#' behind; rostool strips the whole comment",
        lambda ros2, tool: tool.stdout == _no_comments(ros2.stdout),
    ),
}
# cases where ros2 would wait for ever: both are ended by their timeout
FOREVER = {"topic echo --once /parity_missing"}


def _same(case: Case, ros2: Run, tool: Run) -> bool:
    if tool.code != ros2.code or case.normalize(tool.stdout) != case.normalize(ros2.stdout):
        return False
    return not case.error or len(tool.stderr_lines) == 1


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_same_as_ros2(graph: ParityGraph, case: Case) -> None:
    if case.id in FOREVER:
        case = dataclasses.replace(case, timeout=6)
    outcome = graph.compare(case, direct=case.id in DIRECT)
    ros2 = outcome.ros2
    assert case.error == (ros2.code not in (0, None)), f"ros2 {case.id}: exit {ros2.code}: {ros2.stderr}"
    failed = []
    for backend in BACKENDS:
        tool = outcome.tools[backend]
        if case.id in DELIBERATE:
            why, check = DELIBERATE[case.id]
            judge(case, backend, SAME if _same(case, ros2, tool) else DIFFERS, why)
            if not check(ros2, tool):
                failed.append(f"{backend}: not the documented difference ({why})")
            continue
        ok = _same(case, ros2, tool)
        judge(case, backend, SAME if ok else DIFFERS)
        if not ok:
            failed.append(_describe(backend, case, ros2, tool))
    for backend, tool in outcome.direct.items():
        if not _same(case, ros2, tool):
            failed.append("without the daemon: " + _describe(backend, case, ros2, tool))
    assert not failed, "\n".join(failed)


# listings and echoes asked once more without rostool's daemon (the direct paths' referee; the daemon answers
# the rest as it does for users): one of each verb that lists, with its richest form; the plain echo and
# one with a QoS of its own
DIRECT = {
    "topic echo --once /chatter",
    "topic echo --once --qos-reliability best_effort /chatter",
    "node list",
    "node info /parity_server",
    "topic list -v",
    "topic info -v /chatter",
    "service list -t",
    "action info -t /fibonacci",
    "param list",
}


def _describe(backend: str, case: Case, ros2: Run, tool: Run) -> str:
    import difflib

    diff = "".join(
        difflib.unified_diff(
            case.normalize(ros2.stdout).splitlines(True), case.normalize(tool.stdout).splitlines(True),
            "ros2", f"rostool ({backend})", n=1,
        )
    )  # fmt: skip
    return (
        f"{backend}: exit {tool.code} (ros2: {ros2.code})\n{diff}\n"
        f"rostool's stderr: {tool.stderr_lines}\nros2's stderr: {ros2.stderr.strip()[-300:]}"
    )


# --- flags: each verb's options in `ros2 VERB -h` against rostool's ------------------------------------
VERBS = tuple(
    f"{tool} {verb}"
    for tool, verbs in (
        ("node", "list info"), ("topic", "list info type find echo hz bw delay pub"),
        ("service", "list type find call echo info"), ("action", "list info send_goal type"),
        ("param", "list get set delete describe dump load"),
        ("interface", "list show proto package packages"),
    )
    for verb in verbs.split()
)  # fmt: skip
# ros2's flags rostool does not have yet, and why
KNOWN_MISSING: dict[tuple[str, str], str] = {}


# `ros2 VERB -h` for every VERB in one run of ros2's interpreter: the `ros2` script's main() (ros2cli.cli),
# called once per verb, instead of 34 runs at 0.35 s of CPU each
HELPS = """
import contextlib, io, json, sys
from ros2cli.cli import main
helps, verbs = {}, sys.argv[1:]
for verb in verbs:
    sys.argv = ["ros2", *verb.split(), "-h"]  # as the script runs main(): ros2cli reads sys.argv too
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
        main()
    helps[verb] = out.getvalue()
print(json.dumps(helps))
"""


def _ros2_helps(graph_env: dict[str, str]) -> dict[str, str]:
    """ros2's help of each verb of VERBS."""
    python = ROS2.parent / "python"
    done = subprocess.run(
        [str(python), "-c", HELPS, *VERBS], capture_output=True, text=True, env=graph_env, timeout=120
    )
    assert done.returncode == 0, done.stderr
    return dict(json.loads(done.stdout))


def _ros2_flags(help_text: str) -> set[str]:
    """The option strings of ros2's help for a verb (its `options:` section)."""
    out = help_text
    flags: set[str] = set()
    section = False
    for line in out.splitlines():
        section = section or line.startswith("options:")
        if section and line.startswith("  -"):
            spec = re.split(r"\s{2,}", line.strip())[0]
            flags |= {part.split()[0] for part in spec.split(", ")}
    return flags - {"-h", "--help"}


def _rostool_command(verb: str) -> click.Command:
    ctx = click.Context(root)
    command: click.Command | None = root
    for part in verb.split():
        assert isinstance(command, click.Group)
        ctx = click.Context(command, parent=ctx, info_name=part)
        command = command.get_command(ctx, part)
    assert command is not None, verb
    return command


def _rostool_flags(verb: str, hidden: bool) -> set[str]:
    """The option strings of rostool's VERB (its hidden ones too if `hidden`: they exist for ros2's sake)."""
    command = _rostool_command(verb)
    options = [p for p in command.params if isinstance(p, click.Option) and (hidden or not p.hidden)]
    return {flag for p in options for flag in (*p.opts, *p.secondary_opts)} - {"-h", "--help"}


def _flag_help(verb: str, flag: str) -> str:
    """The first sentence of rostool's help for FLAG of VERB."""
    command = _rostool_command(verb)
    option = next(
        p for p in command.params if isinstance(p, click.Option) and flag in (*p.opts, *p.secondary_opts)
    )
    return (option.help or "").split(". ")[0].rstrip(".")


def test_flags_against_ros2() -> None:
    require_ros2cli()
    theirs = {verb: _ros2_flags(text) for verb, text in _ros2_helps(ros2_env()).items()}
    unexpected = []
    for verb in VERBS:
        for flag in sorted(theirs[verb] - _rostool_flags(verb, hidden=True)):
            why = KNOWN_MISSING.get((verb, flag), "")
            judge(Case(verb, flag, (verb, flag)), "both", MISSING, why)
            if not why:
                unexpected.append(f"{verb} {flag}")
        for flag in sorted(_rostool_flags(verb, hidden=False) - theirs[verb]):
            judge(Case(verb, flag, (verb, flag)), "both", ONLY_ROSTOOL, _flag_help(verb, flag))
    record()
    assert not unexpected, f"ros2 flags rostool lacks (add them, or say why in KNOWN_MISSING): {unexpected}"


# a byte array with 0xff, from a parameter file as ros2 param dump writes it (YAML !!binary single bytes)
BLOB_FILE = "/parity_server:\n  ros__parameters:\n    blob:\n    - !!binary AQ==\n    - !!binary /w==\n"


LOADS_BINARY = (
    "rostool loads the byte arrays `param dump` writes (`!!binary` items); Jazzy's ros2 refuses its own "
    "dump's (it reads them as a string array)"
)


def test_byte_array_round_trip(graph: ParityGraph) -> None:
    """Loaded by ros2 and by rostool alike, then read back by both: get, dump, describe."""
    blob = graph.tmp / "blob.yaml"
    blob.write_text(BLOB_FILE)
    steps = [
        Case("param load", "(!!binary bytes)", ("param", "load", "/parity_server", str(blob)),
             name="param load /parity_server BLOB_FILE"),
        case("param get", "(byte array with 0xff)", "param", "get", "/parity_server", "blob"),
        case("param get", "--hide-type (bytes)", "param", "get", "--hide-type", "/parity_server", "blob"),
        case("param dump", "(byte array with 0xff)", "param", "dump", "/parity_server"),
    ]  # fmt: skip
    failed = []
    for step in steps:
        outcome = graph.compare(step)
        assert outcome.ros2.code == 0, outcome.ros2.stderr
        for backend in BACKENDS:
            tool = outcome.tools[backend]
            if step is steps[0]:  # ros2 of Jazzy cannot load the byte arrays its dump writes
                assert "Set parameter blob failed: Wrong parameter type" in outcome.ros2.stderr
                judge(step, backend, DIFFERS, LOADS_BINARY)
                if tool.stdout != "Set parameter blob successful\n":
                    failed.append(f"{backend}: {LOADS_BINARY}: {tool.stdout} {tool.stderr_lines}")
                continue
            ok = _same(step, outcome.ros2, tool)
            judge(step, backend, SAME if ok else DIFFERS)
            if not ok:
                failed.append(_describe(backend, step, outcome.ros2, outcome.tools[backend]))
    assert graph.outcomes[-3].ros2.stdout == "Byte values are: [b'\\x01', b'\\xff']\n"
    assert not failed, "\n".join(failed)


# --- verbs that run until Ctrl+C: their first reports, then SIGINT ------------------------------------
CTRL_C = (
    "ros2 exits 2 on Ctrl+C (its SIGINT number); rostool exits 130, the shell's convention for a command "
    "ended by SIGINT, as every rostool verb does"
)
STREAMS = [
    # (case, the line that starts each report, reports to wait for)
    (case("topic hz", "", "topic", "hz", "/chatter", normalize=digits_zeroed), "average rate:", 2),
    (case("topic hz", "--window", "topic", "hz", "--window", "3", "/chatter", normalize=digits_zeroed),
     "average rate:", 2),
    (case("topic bw", "", "topic", "bw", "/chatter", normalize=digits_zeroed), "", 3),
    (case("topic delay", "", "topic", "delay", "/stamped", normalize=digits_zeroed), "average delay:", 2),
    (case("topic echo", "(until Ctrl+C)", "topic", "echo", "/chatter", normalize=digits_zeroed), "data:", 2),
]  # fmt: skip


def _until_reports(proc: subprocess.Popen[str], start: str, reports: int, deadline: float) -> str:
    """stdout until `reports` report starts and one more line were seen (or the deadline), then SIGINT."""
    assert proc.stdout is not None
    lines: list[str] = []
    while time.monotonic() < deadline and sum(line.startswith(start) for line in lines) <= reports:
        ready, _, _ = select.select([proc.stdout], [], [], 0.2)
        if ready:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
    proc.send_signal(2)
    try:
        rest, _ = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        rest, _ = proc.communicate()
    return "".join(lines) + rest


def _without_not_yet(text: str) -> str:
    """ros2 bw/hz print "does not appear to be published yet" on stdout when their new node has not yet
    discovered the publisher (discovery's timing, not the data; rostool says it on stderr)."""
    return "".join(line for line in text.splitlines(keepends=True) if not _NOT_YET.match(line))


_NOT_YET = re.compile(r"WARNING: topic \[.*\] does not appear to be published yet")


def _reports(text: str, start: str, reports: int) -> str:
    """The first `reports` whole reports (each from a line starting with `start` to the next one)."""
    lines = text.splitlines(keepends=True)
    starts = [i for i, line in enumerate(lines) if line.startswith(start)]
    return "".join(lines[starts[0] : starts[reports]]) if len(starts) > reports else text


@pytest.mark.parametrize(("stream", "start", "reports"), STREAMS, ids=lambda v: getattr(v, "id", ""))
def test_streams_until_ctrl_c(graph: ParityGraph, stream: Case, start: str, reports: int) -> None:
    commands = {"ros2": (graph.ros2_command(list(stream.args)), graph.ros2_env)}
    # rostool through its daemons, which relay the subscription, as users run it
    commands |= {b: graph.rostool_command(b, list(stream.args), served=True) for b in BACKENDS}
    procs = {
        who: subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for who, (command, env) in commands.items()
    }
    deadline = time.monotonic() + 30
    with ThreadPoolExecutor(len(procs)) as pool:
        outs = dict(
            zip(
                procs,
                pool.map(lambda p: _until_reports(p, start, reports, deadline), procs.values()),
                strict=True,
            )
        )
    runs = {
        who: Run(procs[who].returncode, _reports(_without_not_yet(outs[who]), start, reports), "")
        for who in procs
    }
    failed = []
    for backend in BACKENDS:
        tool, ros2 = runs[backend], runs["ros2"]
        same_text = stream.normalize(tool.stdout) == stream.normalize(ros2.stdout)
        # the text is ros2's; the exit status on Ctrl+C deliberately is not
        judge(stream, backend, DIFFERS, CTRL_C if same_text else "")
        if not same_text:
            failed.append(_describe(backend, stream, ros2, tool))
        if (ros2.code, tool.code) != (2, 130):
            failed.append(f"{backend}: Ctrl+C exits {tool.code} (ros2: {ros2.code}); {CTRL_C}")
    assert not failed, "\n".join(failed)


# --- two nodes of one name (ros2node's test_cli_duplicate_node_names): listed twice, warned about --------
TWIN = ["--name", "parity_twin", "--talk", "/twin_chatter"]
TWIN_CASES = [
    (listing("node list", "(duplicate names)", "node", "list"), "WARNING: Be aware that there are nodes"),
    (listing("node list", "-c (duplicate names)", "node", "list", "-c"), ""),
    (listing("node info", "(duplicate names)", "node", "info", "/parity_twin"), "There are 2 nodes in the"),
]


@pytest.fixture(scope="class")
def twins(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ParityGraph]:
    """The twins' graph (two peers, ros2's daemon and two of rostool's), ended once the worker's run of
    TestTwins' cases is: module-scoped, it ran on until that worker left the module."""

    def ready(made: ParityGraph) -> bool:
        return made.ros2_daemon.nodes() == ["/parity_twin", "/parity_twin"]

    with parity_graph(tmp_path_factory.mktemp("twins"), [TWIN, TWIN], ready) as made:
        yield made


# one worker for the three cases, so one twins' graph: only once --dist loadgroup groups again (with pytest
# 9.2 and pytest-xdist 3.8 it groups nothing: pytest-xdist issue 1386)
@pytest.mark.xdist_group("parity_twins")
class TestTwins:
    @pytest.mark.parametrize(("twin_case", "warning"), TWIN_CASES, ids=lambda v: getattr(v, "id", ""))
    def test_duplicate_node_names(self, twins: ParityGraph, twin_case: Case, warning: str) -> None:
        outcome = twins.compare(twin_case)
        assert outcome.ros2.code == 0 and outcome.ros2.stderr.startswith(warning), outcome.ros2.stderr
        failed = []
        for backend in BACKENDS:
            tool = outcome.tools[backend]
            ok = _same(twin_case, outcome.ros2, tool) and (warning in tool.stderr if warning else True)
            judge(twin_case, backend, SAME if ok else DIFFERS)
            if not ok:
                failed.append(
                    _describe(backend, twin_case, outcome.ros2, tool) + f"\nstderr: {tool.stderr_lines}"
                )
        assert not failed, "\n".join(failed)


# --- liveliness both ways: ros2's manual liveliness as rostool shows it, rostool's as ros2 shows it -------
LIVELINESS = ["--qos-liveliness", "manual_by_topic", "--qos-liveliness-lease-duration-seconds", "2.5"]
LEASE_LINES = ("  Liveliness: MANUAL_BY_TOPIC\n", "  Liveliness lease duration: 2500000000 nanoseconds\n")


def _publishing(command: list[str], env: dict[str, str]) -> subprocess.Popen[str]:
    return subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def _stop(proc: subprocess.Popen[str]) -> None:
    proc.send_signal(2)
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def _published(graph: ParityGraph, topic: str) -> Callable[[], bool]:
    """Whether ros2's daemon counts a publisher of `topic` (asked in this process)."""
    return lambda: bool(graph.ros2_daemon.ask("count_publishers", topic))


def _leased(endpoints: list[dict[str, Any]] | None) -> bool:
    """A publisher with the 2.5 s lease among a daemon's `topic_endpoints` rows."""
    return any(e["qos"].get("liveliness_lease_duration") == 2.5 for e in endpoints or ())


def test_liveliness_both_ways(graph: ParityGraph) -> None:
    """ros2 topic pub with manual_by_topic liveliness and a 2.5 s lease: rostool's topic info -v prints
    ros2's text for it; rostool's pub with the same flags: ros2's topic info -v shows that kind and lease."""
    message = ["std_msgs/msg/String", "{data: alive}"]
    ros2_pub = ["topic", "pub", "-r", "5", *LIVELINESS, "/parity_lively", *message]
    talker = _publishing(graph.ros2_command(ros2_pub), graph.ros2_env)
    try:
        info = ["topic", "info", "-v", "/parity_lively"]
        assert wait_ros2(graph, info, LEASE_LINES[1], gate=_published(graph, "/parity_lively")), talker.stderr
        # and rostool's daemons (each a moment behind or ahead of ros2's), asked in this process
        assert wait_until(
            lambda: all(
                _leased(daemon_answer(graph.daemons[b], "topic_endpoints", "/parity_lively"))
                for b in BACKENDS
            ),
            20,
        ), "rostool's daemons never saw ros2's publisher"
        step = listing("topic info", "-v (manual liveliness)", "topic", "info", "-v", "/parity_lively",
                       normalize=gids)  # fmt: skip
        outcome = graph.compare(step)
    finally:
        _stop(talker)
    failed = []
    for backend in BACKENDS:
        tool = outcome.tools[backend]
        ok = _same(step, outcome.ros2, tool)
        judge(step, backend, SAME if ok else DIFFERS)
        if not ok:
            failed.append(_describe(backend, step, outcome.ros2, tool))
    for backend in BACKENDS:
        topic = f"/parity_lively_{backend}"
        args = ["topic", "pub", "-r", "5", *LIVELINESS, topic, *message]
        command, env = graph.rostool_command(backend, args)
        proc = _publishing(command, env)
        try:
            seen = wait_ros2(
                graph, ["topic", "info", "-v", topic], LEASE_LINES[1], gate=_published(graph, topic)
            )
            shown = graph.ros2(["topic", "info", "-v", topic]).stdout
        finally:
            _stop(proc)
        if not (seen and all(line in shown for line in LEASE_LINES)):
            failed.append(f"{backend}: ros2 topic info -v of rostool's publisher:\n{shown}")
    assert not failed, "\n".join(failed)


# --- param get NODE P1 P2 ...: Jazzy's ros2 takes one name; rostool prints several as ros2cli after Jazzy
# does (each name, then Jazzy's line for it indented; --hide-type: `name: value`) -------------------------
SEVERAL = ("count", "label", "blob", "gains", "flag")


def test_param_get_several(graph: ParityGraph) -> None:
    with ThreadPoolExecutor(4) as pool:
        typed = list(pool.map(lambda p: graph.ros2(["param", "get", "/parity_server", p]), SEVERAL))
        bare = list(
            pool.map(lambda p: graph.ros2(["param", "get", "--hide-type", "/parity_server", p]), SEVERAL)
        )
    assert all(run.code == 0 for run in typed + bare), [run.stderr for run in typed + bare]
    expected = "".join(f"{p}:\n  {run.stdout}" for p, run in zip(SEVERAL, typed, strict=True))
    expected_bare = "".join(f"{p}: {run.stdout}" for p, run in zip(SEVERAL, bare, strict=True))
    failed = []
    for backend in BACKENDS:
        for flags, want in (([], expected), (["--hide-type"], expected_bare)):
            got = graph.rostool(backend, ["param", "get", *flags, "/parity_server", *SEVERAL])
            if (got.code, got.stdout) != (0, want):
                failed.append(
                    f"{backend} {flags}: exit {got.code}\n{got.stdout}\nwanted:\n{want}{got.stderr}"
                )
        missing = graph.rostool(backend, ["param", "get", "/parity_server", "count", "parity_nope"])
        if (
            missing.code != 1
            or missing.stdout
            or missing.stderr_lines
            != ["rostool: Parameter(s) 'parity_nope' not available on node /parity_server"]
        ):
            failed.append(f"{backend}: a missing name: exit {missing.code} {missing.stderr_lines}")
    assert not failed, "\n".join(failed)


# --- param load with wildcards (ros2param's test_verb_load): `/**` applies to every node unless
# --no-use-wildcard, the node's own section overrides it; a node or file that is not there fails ---------
WILDCARD = "/**:\n  ros__parameters:\n    label: wild\n    count: 12345\n"
OVERLAY = "/parity_server:\n  ros__parameters:\n    label: override\n"
BEFORE = "/parity_server:\n  ros__parameters:\n    label: before\n    count: 1\n"


def test_param_load_wildcards(graph: ParityGraph) -> None:
    wildcard, both, before = (graph.tmp / f"{name}.yaml" for name in ("wildcard", "overlay", "before"))
    wildcard.write_text(WILDCARD)
    both.write_text(WILDCARD + OVERLAY)
    before.write_text(BEFORE)
    tools: dict[str, Callable[[list[str]], Run]] = {"ros2": graph.ros2}
    tools |= {b: lambda args, b=b: graph.rostool(b, args) for b in BACKENDS}

    pool = ThreadPoolExecutor(2)  # two independent calls at a time: two names, two failures

    def values() -> tuple[str, str]:
        """label and count as `ros2 param get --hide-type` prints them, from one `ros2 param dump`."""
        dumped = yaml.safe_load(graph.ros2(["param", "dump", "/parity_server"]).stdout)
        held = dumped["/parity_server"]["ros__parameters"]
        return str(held["label"]), str(held["count"])

    seen: dict[str, list[object]] = {}
    for who, run in tools.items():
        assert graph.ros2(["param", "load", "/parity_server", str(before)]).code == 0
        refused = run(["param", "load", "/parity_server", str(wildcard), "--no-use-wildcard"])
        kept = values()
        loaded = run(["param", "load", "/parity_server", str(wildcard)])
        wild = values()
        overlaid = run(["param", "load", "/parity_server", str(both)])
        over = values()
        no_node, no_file = pool.map(run, (
            ["param", "load", "/parity_nobody", str(wildcard)],
            ["param", "load", "/parity_server", str(graph.tmp / "parity_nofile.yaml")],
        ))  # fmt: skip
        seen[who] = [
            refused.code, kept, loaded.code, loaded.stdout, wild, overlaid.code, overlaid.stdout, over,
            no_node.code, no_file.code,
        ]  # fmt: skip
        if who != "ros2":
            errors = (refused, no_node, no_file)
            seen[who].append([len(e.stderr_lines) == 1 and not e.stdout for e in errors])
    pool.shutdown()
    # ros2's own test's facts
    ros2 = seen["ros2"]
    assert ros2[0] != 0 and ros2[1] == ("before", "1"), ros2
    assert ros2[4] == ("wild", "12345") and ros2[7] == ("override", "12345"), ros2
    assert ros2[8] != 0 and ros2[9] != 0, ros2
    failed = [f"{b}: {seen[b]}\nros2: {ros2}" for b in BACKENDS if seen[b] != [*ros2, [True, True, True]]]
    for backend in BACKENDS:
        step = Case("param load", "(wildcards)", ("param", "load"), name="param load NODE WILDCARD_FILES")
        judge(step, backend, SAME if seen[backend] == [*ros2, [True, True, True]] else DIFFERS)
    assert not failed, "\n".join(failed)
