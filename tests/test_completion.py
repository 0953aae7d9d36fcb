"""Shell completion through the real mechanism: `rostool` run the way bash's completion function runs it
(`_ROSTOOL_COMPLETE=bash_complete`, COMP_WORDS, COMP_CWORD), against a real ROS 1 master with rostopic,
real rclpy peers (DDS and rclpy backends), the real bags of /work/shared/testdata and the type stores."""

from __future__ import annotations

import shlex
import socket
import subprocess
import sys
import xmlrpc.client
from collections.abc import Callable
from pathlib import Path

import pytest

from rostool.completion import TIMEOUT_ENV
from tests.ros2_peers import RclpyPeer, peer_env, peer_python
from tests.support import TESTDATA, debian_popen, free_port, ros1_env, stop, wait_until

ROSTOOL = Path(sys.executable).with_name("rostool")
EXAMPLE_BAG = TESTDATA / "ros1" / "example.bag"
TALKER_MCAP = TESTDATA / "ros2" / "talker_mcap"
GENEROUS = "20"  # lookup budget for the tests that assert names: the machine may be loaded


def complete(
    words: list[str], env: dict[str, str], command: list[str] | None = None, shell: str = "bash"
) -> list[tuple[str, str]]:
    """(type, value) candidates for the last word of `rostool WORDS...`; completion never writes to
    stderr and always exits 0."""
    line = " ".join(shlex.quote(w) for w in ["rostool", *words])
    run = subprocess.run(
        command or [str(ROSTOOL)],
        env={
            **env,
            "_ROSTOOL_COMPLETE": f"{shell}_complete",
            "COMP_WORDS": line,
            "COMP_CWORD": str(len(words)),
        },
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    assert run.stderr == ""
    return [tuple(row.split(",", 1)) for row in run.stdout.splitlines() if row]  # type: ignore[misc]


def values(words: list[str], env: dict[str, str], command: list[str] | None = None) -> list[str]:
    return [value for kind, value in complete(words, env, command) if kind == "plain"]


def bag_topics(path: Path) -> list[str]:
    """The bag's topics as rosbags itself reads them (the reference)."""
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return sorted({conn.topic for conn in reader.connections})


# --- ROS 1: Debian's rosmaster and rostopic --------------------------------------------------------------
def test_ros1_graph_names(debian_master: dict[str, str]) -> None:
    env = {**debian_master, TIMEOUT_ENV: GENEROUS}
    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    publisher = debian_popen(["rostopic", "pub", "/chatter", "std_msgs/String", "data: hi", "-r", "1"], env)
    try:
        # the master's own answers are the reference (rostopic list/rosnode list are slow on a loaded box)
        assert wait_until(
            lambda: ["/chatter", "std_msgs/String"] in master.getPublishedTopics("/t", "")[2], 30
        )
        master.setParam("/t", "/wheel/radius", 0.05)
        publishers = master.getSystemState("/t")[2][0]
        nodes = [node for topic, names in publishers if topic == "/chatter" for node in names]
        assert len(nodes) == 1 and nodes[0].startswith("/rostopic")

        assert values(["topic", "echo", "/"], env) == ["/chatter"]
        assert values(["topic", "hz", "chat"], env) == ["chatter"]  # relative names complete relative
        assert values(["node", "info", "/ros"], env) == nodes
        assert f"{nodes[0]}/get_loggers" in values(["service", "type", ""], env)
        assert values(["param", "get", "/wh"], env) == ["/wheel/radius"]
        assert values(["bag", "record", "/ch"], env) == ["/chatter"]  # record takes the live graph's
        assert values(["topic", "pub", "/x", "std_msgs/Str"], env) == ["std_msgs/String"]
    finally:
        stop(publisher)


def test_ros1_without_a_master_gives_nothing(tmp_path: Path) -> None:
    env = ros1_env(free_port(), tmp_path)  # nobody listens there
    assert complete(["--ros1", "node", "info", "/"], env) == []


def test_ros1_master_that_never_answers_is_left_behind(tmp_path: Path) -> None:
    """A master that accepts the connection and never replies: the budget ends the lookup (default
    budget, no ROSTOOL_COMPLETE_TIMEOUT) and the process still exits."""
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(8)
        env = ros1_env(silent.getsockname()[1], tmp_path)
        assert complete(["--ros1", "topic", "echo", "/"], env) == []


# --- ROS 2: real rclpy peers --------------------------------------------------------------------------
PEER_ARGS = ("--name", "talker", "--talk", "/chatter", "--service", "/set_flag", "--action", "/fibonacci",
             "--params")  # fmt: skip


def test_ros2_graph_names(
    distro: str, graph_env: dict[str, str], start_peer: Callable[..., RclpyPeer], tmp_path: Path
) -> None:
    """Names of a real rclpy node through rostool's DDS backend, then through its rclpy backend (run in the
    peer venv with --ros2-backend rclpy)."""
    start_peer(*PEER_ARGS)
    env = {**graph_env, TIMEOUT_ENV: GENEROUS}
    assert values(["topic", "echo", "/ch"], env) == ["/chatter"]
    assert "/talker" in values(["node", "info", ""], env)
    assert values(["service", "call", "/set_"], env) == ["/set_flag"]
    assert values(["action", "info", ""], env) == ["/fibonacci"]
    params = values(["param", "get", "/talker", ""], env)  # ros2 param: NODE, then its parameters
    assert {"flag", "count", "speed", "use_sim_time"} <= set(params)
    assert values(["param", "describe", "/talker", "spe"], env) == ["speed"]

    env = peer_env(env, tmp_path)
    command = [str(peer_python(distro)), "-m", "rostool"]
    assert values(["--ros2-backend", "rclpy", "topic", "info", "/ch"], env, command) == ["/chatter"]
    assert "/talker" in values(["--ros2-backend", "rclpy", "node", "info", "/t"], env, command)
    assert "flag" in values(["--ros2-backend", "rclpy", "param", "get", "/talker", "fl"], env, command)


def test_ros2_empty_graph_gives_nothing(graph_env: dict[str, str]) -> None:
    """Nobody on this domain: the default discovery budget passes, no candidates, nothing on stderr."""
    assert complete(["--ros2", "topic", "echo", "/"], graph_env) == []
    assert complete(["--ros2", "param", "get", ""], graph_env) == []


# --- bags, files, types: no graph ----------------------------------------------------------------------
def test_bag_topics_from_the_bag_on_the_command_line() -> None:
    env = {"PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    ros1_topics = bag_topics(EXAMPLE_BAG)
    assert values(["bag", "echo", str(EXAMPLE_BAG), ""], env) == ros1_topics
    assert values(["--ros1", "bag", "play", str(EXAMPLE_BAG), "--topics", "/turtle1/"], env) == [
        t for t in ros1_topics if t.startswith("/turtle1/")
    ]
    assert values(["bag", "convert", str(EXAMPLE_BAG), "out.mcap", "--topics", "/tf"], env) == [
        "/tf", "/tf_static"
    ]  # fmt: skip
    ros2_topics = bag_topics(TALKER_MCAP)
    assert values(["--ros2", "bag", "play", str(TALKER_MCAP), "--topics", ""], env) == ros2_topics
    assert values(["bag", "export", str(TALKER_MCAP), "--topics", ""], env) == ros2_topics
    # a bag path still being typed completes as a file
    prefix = str(EXAMPLE_BAG)[:-5]
    assert complete(["bag", "echo", prefix], env) == [("file", prefix)]
    assert complete(["bag", "info", prefix], env) == [("file", prefix)]


def test_type_names_in_each_versions_form() -> None:
    env = {"PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    assert values(["--ros1", "msg", "show", "std_msgs/Str"], env) == ["std_msgs/String"]
    assert values(["--ros2", "msg", "show", "std_msgs/msg/Str"], env) == ["std_msgs/msg/String"]
    assert values(["msg", "show", "std_msgs/msg/Str"], env) == ["std_msgs/msg/String"]  # the name says
    assert values(["--ros2", "topic", "pub", "/x", "geometry_msgs/Twi"], env) == [
        "geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped", "geometry_msgs/msg/TwistWithCovariance",
        "geometry_msgs/msg/TwistWithCovarianceStamped",
    ]  # fmt: skip
    assert {"std_srvs/Empty", "std_srvs/SetBool", "std_srvs/Trigger"} <= set(
        values(["--ros1", "srv", "show", "std_srvs/"], env)
    )
    assert "std_srvs/srv/SetBool" in values(["--ros2", "srv", "show", "std_srvs/"], env)
    assert values(["--ros2", "action", "show", "test_msgs/"], env) == ["test_msgs/action/Fibonacci"]


def test_zsh_and_fish_scripts_and_zsh_candidates() -> None:
    env = {"PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    for shell, marker in (("bash", "complete -o nosort -F"), ("zsh", "#compdef rostool"),
                          ("fish", "complete --no-files --command rostool")):  # fmt: skip
        script = subprocess.run([str(ROSTOOL)], env={**env, "_ROSTOOL_COMPLETE": f"{shell}_source"},
                                capture_output=True, text=True, timeout=30)  # fmt: skip
        assert marker in script.stdout
    zsh = subprocess.run(
        [str(ROSTOOL)],
        env={**env, "_ROSTOOL_COMPLETE": "zsh_complete", "COMP_WORDS": "rostool --ros1 msg show std_msgs/Str",
             "COMP_CWORD": "4"},
        capture_output=True, text=True, timeout=30,
    )  # fmt: skip
    assert zsh.stdout.splitlines()[:2] == ["plain", "std_msgs/String"]


def test_attach_imports_nothing_heavy() -> None:
    """Attaching happens whenever a command loads: importing the module pulls in no ROS machinery."""
    probe = (
        "import sys, rostool.completion\n"
        "heavy = ('rosbags', 'cyclonedds', 'rclpy', 'rostool.graph', 'rostool.bag', 'rostool.interfaces')\n"
        "print(sorted(m for m in sys.modules if m.startswith(heavy)))"
    )
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=30)
    assert run.stdout.strip() == "[]", run.stderr


@pytest.mark.parametrize("words", [["topic", "echo", "-"], ["bag", "info", "--"]])
def test_options_still_complete(words: list[str]) -> None:
    """Option names are click's own completion, unchanged."""
    env = {"PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    assert all(value.startswith("-") for _kind, value in complete(words, env))
    assert complete(words, env)
