"""The rclpy backend (`--ros2-backend rclpy`): selection, `doctor`, bad input (a broken rclpy, a missing RMW
library, types rclpy cannot import), and the topic, node, service, parameter and action verbs against real
rclpy nodes of Jazzy and Kilted (Fast DDS). Services, parameters, actions and bags are also checked value by
value on both backends in test_ros2_fastdds_rpc.py and test_ros2_real_bags.py.

rostool runs in the distro's peer venv (test.sh installs it there) with the peers' loopback-only Fast DDS
profile; where the argument forms are the same, its output must equal the DDS backend's.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.ros2_backends import middleware_line
from tests.ros2_peers import (
    RclpyPeer,
    assert_loopback_only,
    bound_addresses,
    peer_env,
    peer_python,
    rostool_rclpy,
    rostool_rclpy_popen,
)
from tests.support import Watched, rostool, stop, wait_until
from tests.test_ros2_fastdds_rpc import in_lanes

Start = Callable[..., RclpyPeer]


def docs(text: str) -> list[str]:
    return [doc.strip() for doc in text.split("---") if doc.strip()]


def one_error_line(done: subprocess.CompletedProcess[str], *words: str) -> str:
    assert done.returncode != 0, done.stdout
    lines = [
        line
        for line in done.stderr.strip().splitlines()
        if not line.startswith("WARNING: ") and not middleware_line(line)
    ]
    assert len(lines) == 1, done.stderr
    assert "Traceback" not in done.stderr
    for word in words:
        assert word in lines[0], (word, lines[0])
    return lines[0]


# --- selection, doctor and bad input ---------------------------------------------------------------


def test_without_rclpy_auto_is_dds_and_rclpy_is_one_line(graph_env: dict[str, str]) -> None:
    """The test venv has no rclpy: auto serves ROS 2 with the DDS backend, and asking for rclpy fails in
    one line naming the way out."""
    report = json.loads(rostool(["doctor", "--json"], graph_env).stdout)
    assert report["ros_version"] == 2
    assert report["ros2"]["backend"] == "dds" and "rclpy is not installed" in report["ros2"]["reason"]
    assert report["ros2"]["domain_id"] == int(graph_env["ROS_DOMAIN_ID"])
    assert report["ros2"]["discovery_range"] == "LOCALHOST"
    asked = rostool(["--ros2-backend", "rclpy", "topic", "list"], graph_env)
    one_error_line(asked, "rclpy is not installed", "--ros2-backend dds")
    by_env = rostool(["topic", "list"], {**graph_env, "ROSTOOL_ROS2_BACKEND": "rclpy"})
    one_error_line(by_env, "rclpy is not installed", "--ros2-backend dds")
    bad = {**graph_env, "ROSTOOL_ROS2_BACKEND": "fast"}
    one_error_line(rostool(["topic", "list"], bad), "ROSTOOL_ROS2_BACKEND='fast'", "auto, rclpy, dds")
    doctor = rostool(["doctor"], bad)  # doctor shows the problem in its report, and fails
    assert doctor.returncode == 1 and "ROSTOOL_ROS2_BACKEND='fast' is not valid" in doctor.stdout


def test_broken_rclpy_falls_back_in_auto_and_is_one_line_when_asked(
    graph_env: dict[str, str], tmp_path: Path
) -> None:
    """rclpy present but not importable (as a ROS 2 sourced for another Python is): auto uses DDS and
    doctor says why; --ros2-backend rclpy is one line naming it and the way out."""
    fake = tmp_path / "site" / "rclpy"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError(\"No module named 'rclpy._rclpy_pybind11'\")\n")
    env = {**graph_env, "PYTHONPATH": str(fake.parent)}
    report = json.loads(rostool(["doctor", "--json"], env).stdout)
    assert report["ros2"]["backend"] == "dds"
    assert "does not import" in report["ros2"]["reason"] and "_rclpy_pybind11" in report["ros2"]["reason"]
    line = one_error_line(rostool(["--ros2-backend", "rclpy", "node", "list"], env), "--ros2-backend dds")
    assert "_rclpy_pybind11" in line and f"Python {sys.version_info.major}.{sys.version_info.minor}" in line
    doctor = rostool(["--ros2-backend", "rclpy", "doctor"], env)
    assert doctor.returncode == 1 and "_rclpy_pybind11" in doctor.stdout


def test_help_imports_neither_backend(distro: str) -> None:
    probe = (
        "import sys, io, contextlib\n"
        "from rostool.cli import root\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        root.main(['--help'])\n    except SystemExit:\n        pass\n"
        "print([m for m in ('rclpy', 'cyclonedds', 'rostool.graph') if m in sys.modules])"
    )
    out = subprocess.run([str(peer_python(distro)), "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_doctor_reports_rclpy_and_the_choice(graph_env: dict[str, str], tmp_path: Path, distro: str) -> None:
    env = peer_env(graph_env, tmp_path)
    python = str(peer_python(distro))

    def doctor(*args: str, **extra: str) -> dict:
        # --listen 0: the peers' environment is SUBNET for rmw (their profile keeps them on loopback), and
        # doctor must not join multicast groups on the host's interfaces (the network rule)
        done = subprocess.run([python, "-m", "rostool", *args, "doctor", "--json", "--listen", "0"],
                              env={**env, **extra},
                              capture_output=True, text=True, timeout=30)  # fmt: skip
        report = json.loads(done.stdout)
        # nothing runs on this test's domain: other tests' participants on this machine may fail the
        # network's domain check (exit 1), never anything else
        failed = [check["name"] for check in report["checks"] if not check["ok"]]
        assert done.returncode == (1 if failed else 0) and failed in ([], ["domain"]), done.stderr
        return report["ros2"]  # type: ignore[no-any-return]

    auto = doctor()
    assert (auto["backend"], auto["reason"]) == ("rclpy", "auto: rclpy imports")
    assert (auto["rmw"], auto["distro"]) == ("rmw_fastrtps_cpp", distro)
    assert auto["domain_id"] == int(graph_env["ROS_DOMAIN_ID"]) and auto["domain_id_from"] == "ROS_DOMAIN_ID"
    assert auto["discovery_range"] == "SUBNET"  # ROS 2's default: rmw reads the variable, none is set
    assert auto["middleware_settings"]["FASTDDS_DEFAULT_PROFILES_FILE"].endswith("fastdds_loopback.xml")
    assert doctor(ROSTOOL_ROS2_BACKEND="dds")["backend"] == "dds"
    assert (
        doctor("--ros2-backend", "dds", ROSTOOL_ROS2_BACKEND="rclpy")["reason"]
        == "asked for by --ros2-backend"
    )
    text = subprocess.run([python, "-m", "rostool", "doctor", "--listen", "0"], env=env, capture_output=True,
                          text=True).stdout  # fmt: skip
    assert re.search(r"^RMW +: rmw_fastrtps_cpp \(RMW_IMPLEMENTATION\)$", text, re.M), text


def test_unknown_rmw_and_bad_domain_are_one_line(
    graph_env: dict[str, str], tmp_path: Path, distro: str
) -> None:
    """librcl ends the process (exit 102) when RMW_IMPLEMENTATION names a missing library: rostool checks
    first and says so in one line."""
    for extra, words in (
        ({"RMW_IMPLEMENTATION": "rmw_bogus_cpp"}, ("rmw_bogus_cpp", "installed: rmw_fastrtps_cpp", "dds")),
        ({"ROS_DOMAIN_ID": "999"}, ("ROS_DOMAIN_ID",)),
    ):
        env = {**peer_env(graph_env, tmp_path), **extra}  # peer_env names rmw_fastrtps_cpp: replace it
        command = [str(peer_python(distro)), "-m", "rostool", "--ros2-backend", "rclpy", "topic", "list"]
        done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=30)
        assert done.returncode == 1, done
        one_error_line(done, *words)


# --- the verbs against real nodes ------------------------------------------------------------------


@pytest.fixture
def rclpy_tool(
    graph_env: dict[str, str], tmp_path: Path, distro: str
) -> Callable[..., subprocess.CompletedProcess[str]]:
    def run(*args: str, timeout: float = 30) -> subprocess.CompletedProcess[str]:
        return rostool_rclpy(list(args), graph_env, tmp_path, distro, timeout=timeout)

    return run


Tool = Callable[..., subprocess.CompletedProcess[str]]


def test_topic_list_type_find_as_the_dds_backend(
    graph_env: dict[str, str], start_peer: Start, rclpy_tool: Tool
) -> None:
    """The runs only list, side by side; but a rostool on rclpy has a /parameter_events publisher for a
    moment as it starts (rclpy gives every node one; rostool destroys it), which `topic list -v` beside it
    may count: the two `topic list -v` compared run after the others, one after the other."""
    start_peer("--name", "talker", "--talk", "/chatter", "--listen", "/heard")
    # node names only where the DDS backend waits for them too (its listing does not wait for Fast DDS's
    # ros_discovery_info, and may show _NODE_NAME_UNKNOWN_ where rmw knows the node)
    compared = (["topic", "type", "/chatter"], ["topic", "find", "std_msgs/msg/String"],
                ["topic", "info", "/chatter"])  # fmt: skip
    with ThreadPoolExecutor(max_workers=3) as pool:
        lists = [pool.submit(rclpy_tool, "topic", "list") for _ in range(3)]
        pairs = [(pool.submit(rclpy_tool, *args), pool.submit(rostool, args, graph_env)) for args in compared]
        verbose = pool.submit(rclpy_tool, "topic", "list", "-v")
        found = pool.submit(rclpy_tool, "topic", "find", "std_msgs/String")
        as_json = pool.submit(rclpy_tool, "topic", "list", "--json")
    for listing in lists:
        listed = listing.result()
        assert "/chatter" in listed.stdout.split(), listed.stderr
    alone = ["topic", "list", "-v"]
    results = [
        (args, mine.result(), theirs.result()) for args, (mine, theirs) in zip(compared, pairs, strict=True)
    ]
    results.append((alone, rclpy_tool(*alone), rostool(alone, graph_env)))
    for args, mine, theirs in results:
        assert mine.returncode == 0, (args, mine.stderr)
        assert mine.stdout == theirs.stdout, args
    assert " * /chatter [std_msgs/msg/String] 1 publisher" in verbose.result().stdout
    assert found.result().stdout == "/chatter\n/heard\n"
    listed = {t["name"]: t for t in json.loads(as_json.result().stdout)}
    chatter = {"name": "/chatter", "type": "std_msgs/msg/String", "publishers": ["/talker"]}
    assert listed["/chatter"] == {**chatter, "subscribers": []}
    assert listed["/heard"]["subscribers"] == ["/talker"]


def test_node_list_and_info_as_the_dds_backend(
    graph_env: dict[str, str], start_peer: Start, rclpy_tool: Tool
) -> None:
    start_peer("--name", "talker", "--namespace", "/robot", "--talk", "/chatter", "--listen", "/heard")
    # node list on its own (a rostool on rclpy is a node: one beside it would be listed), the infos together
    nodes = rclpy_tool("node", "list")
    assert nodes.stdout == "/robot/talker\n", nodes.stderr
    with ThreadPoolExecutor() as pool:
        as_json = pool.submit(rclpy_tool, "node", "info", "/robot/talker", "--json")
        as_text = pool.submit(rclpy_tool, "node", "info", "/robot/talker")
        theirs = pool.submit(rostool, ["node", "info", "/robot/talker"], graph_env)
    info = json.loads(as_json.result().stdout)
    assert {"name": "/chatter", "type": "std_msgs/msg/String"} in info["publishers"]
    assert {"name": "/heard", "type": "std_msgs/msg/String"} in info["subscribers"]
    assert "/robot/talker/list_parameters" in [s["name"] for s in info["service_servers"]]
    text = as_text.result().stdout
    assert text.splitlines()[0] == "/robot/talker" and "    /chatter: std_msgs/msg/String" in text
    assert text == theirs.result().stdout


def test_topic_info_verbose_names_the_real_node(start_peer: Start, rclpy_tool: Tool) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--best-effort", "--depth", "7")
    detail = rclpy_tool("topic", "info", "/chatter", "-v", "--json")
    (endpoint,) = json.loads(detail.stdout)["endpoints"]
    assert endpoint["node"] == "/talker"
    assert endpoint["endpoint_type"] == "PUBLISHER"
    assert endpoint["qos"]["reliability"] == "best_effort"
    assert endpoint["qos"]["depth"] is None  # Fast DDS does not announce its history: unknown, as ros2 says
    assert endpoint["type_hash"] == "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
    assert re.fullmatch(r"([0-9a-f]{2}\.){15}[0-9a-f]{2}", endpoint["gid"])
    text = rclpy_tool("topic", "info", "/chatter", "-v").stdout
    assert "Reliability: BEST_EFFORT" in text and "History (Depth): UNKNOWN" in text


def test_echo_receives_the_real_publishers_messages(start_peer: Start, rclpy_tool: Tool) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    echo = rclpy_tool("topic", "echo", "/chatter", "-n", "3", "--json")
    assert echo.returncode == 0, echo.stderr
    numbers = [int(json.loads(line)["data"].removeprefix("hello ")) for line in echo.stdout.splitlines()]
    assert numbers == list(range(numbers[0], numbers[0] + 3))
    text = rclpy_tool("topic", "echo", "/chatter", "-n", "1").stdout
    assert re.fullmatch(r"data: hello \d+\n---\n", text), text


def test_echo_of_a_latched_best_effort_mix_adapts(start_peer: Start, rclpy_tool: Tool) -> None:
    """A transient_local publisher: echo adapts and gets the message sent before it started."""
    start_peer("--name", "latcher", "--talk", "/latched", "--latched", "--count", "1")
    echo = rclpy_tool("topic", "echo", "/latched", "-n", "1", "--json", "--timeout", "10")
    assert echo.returncode == 0, echo.stderr
    assert json.loads(echo.stdout)["data"].startswith("hello ")


@pytest.mark.alone
def test_hz_at_10_hz_and_1_khz(
    graph_env: dict[str, str], tmp_path: Path, distro: str, start_peer: Start, rclpy_tool: Tool
) -> None:
    """hz agrees within 2 % with the rate the publisher itself measured: over the same seconds at 10 Hz, and
    over a burst of exactly 3000 messages at 1 kHz, of which hz must count every one (a Python publisher on
    a loaded machine does not keep exactly 1 kHz, and its rate drifts from one second to the next)."""
    # the 1 kHz hz starts first: its start-up and discovery overlap the 10 Hz window (its talker waits
    # for it, and starts only after that window)
    hz = Watched(rostool_rclpy_popen(["topic", "hz", "/fast", "--json"], graph_env, tmp_path, distro))
    try:
        slow = start_peer("--name", "slow", "--talk", "/slow", "--rate", "10")
        before = len(slow.of("published"))
        out = rclpy_tool("topic", "hz", "/slow", "--json", "--duration", "5.2").stdout
        reports = [json.loads(line) for line in out.splitlines()]
        assert reports, out
        during = slow.of("published")[before + 1 :]
        true_rate = (during[-1]["count"] - during[0]["count"]) / (during[-1]["t"] - during[0]["t"])
        assert abs(reports[-1]["rate"] - true_rate) / true_rate < 0.02, (true_rate, reports[-1])

        fast = start_peer("--name", "fast", "--talk", "/fast", "--rate", "1000", "--depth", "1000",
                          "--count", "3000", "--subs", "1")  # fmt: skip
        sent = fast.wait_for("sent", timeout=60)
        hz.wait_for(lambda out: any(json.loads(line)["received"] == 3000 for line in out.splitlines()
                                    if line.startswith("{")), timeout=10)  # fmt: skip
    finally:
        out, _err = hz.stop()
    last = [json.loads(line) for line in out.splitlines() if line.startswith("{")][-1]
    true_rate = (sent["count"] - 1) / sent["seconds"]
    assert last["received"] == 3000, last
    assert abs(last["rate"] - true_rate) / true_rate < 0.02, (true_rate, last)


def test_bw_measures_the_real_cdr_size(start_peer: Start, rclpy_tool: Tool) -> None:
    start_peer("--name", "talker", "--talk", "/chatter", "--rate", "20")
    out = rclpy_tool("topic", "bw", "/chatter", "--duration", "3.2").stdout  # discovery may take 3 s
    means = re.findall(r"mean: ([\d.]+) ?B", out)  # the same 20 bytes the DDS backend measures
    assert means and float(means[-1]) == 20.0, out


def test_pub_reaches_the_real_subscriber(
    graph_env: dict[str, str], tmp_path: Path, distro: str, start_peer: Start, rclpy_tool: Tool
) -> None:
    peer = start_peer("--name", "listener", "--listen", "/heard")
    once = rclpy_tool("topic", "pub", "/heard", "std_msgs/msg/String", "data: from rostool", "-1")
    assert once.returncode == 0, once.stderr
    assert peer.wait_for("heard")["data"] == "from rostool"
    again = ["topic", "pub", "/heard", "std_msgs/String", "data: again", "-r", "20"]
    repeated = rostool_rclpy_popen(again, graph_env, tmp_path, distro)
    try:
        peer.wait_for("heard", lambda e: e["data"] == "again")
        addresses = bound_addresses(repeated.pid)
    finally:
        stop(repeated)
    assert addresses
    assert_loopback_only(addresses)


def test_a_real_node_sees_rostool_as_a_node(
    graph_env: dict[str, str], tmp_path: Path, distro: str, start_peer: Start
) -> None:
    """Unlike the DDS backend's endpoints, which a Kilted node files under no node, rclpy's are its node's."""
    watcher = start_peer("--name", "watcher", "--watch")
    pub = rostool_rclpy_popen(["topic", "pub", "/from_rostool", "std_msgs/String", "data: x", "-r", "5"],
                              graph_env, tmp_path, distro)  # fmt: skip
    echo = rostool_rclpy_popen(
        ["topic", "echo", "/from_rostool", "std_msgs/msg/String"], graph_env, tmp_path, distro
    )
    me_pub, me_sub = f"/rostool_{pub.pid}", f"/rostool_{echo.pid}"
    try:

        def complete(event: dict) -> bool:
            return (
                me_pub in event["nodes"]
                and me_sub in event["nodes"]
                and event["publishers"].get("/from_rostool") == [me_pub]
                and event["subscribers"].get("/from_rostool") == [me_sub]
                and event["topics"].get("/from_rostool") == ["std_msgs/msg/String"]
            )

        try:
            watcher.wait_for("graph", complete, timeout=20)
        except AssertionError:
            raise AssertionError(f"{me_pub}, {me_sub} not in {watcher.of('graph')[-1:]}") from None
    finally:
        stop(pub)
        stop(echo)


def test_a_type_rosbags_lacks_comes_from_the_class_rclpy_imports(
    graph_env: dict[str, str], tmp_path: Path, distro: str, start_peer: Start, rclpy_tool: Tool
) -> None:
    """test_msgs is in no rosbags store: the rclpy backend describes it from the imported class, .msg
    defaults included, and the DDS backend reading the package's .msg files decodes the same bytes alike."""
    start_peer("--name", "listener", "--listen", "/heard")
    args = ["topic", "pub", "/defaults", "test_msgs/msg/Defaults", "{int32_value: 7}", "-r", "5"]
    pub = rostool_rclpy_popen(args, graph_env, tmp_path, distro)
    try:
        echo = rclpy_tool("topic", "echo", "/defaults", "test_msgs/msg/Defaults", "--once", "--json")
        assert echo.returncode == 0, echo.stderr
        got = json.loads(echo.stdout)
        assert (got["int32_value"], got["bool_value"], got["float64_value"], got["uint8_value"]) == (
            7,
            True,
            1.125,
            200,
        )
        share = peer_python(distro).parent.parent / "share" / "test_msgs"
        dds = rostool(["topic", "echo", "/defaults", "test_msgs/msg/Defaults", "--once", "--json"],
                      {**graph_env, "ROSTOOL_INTERFACES": str(share)})  # fmt: skip
        assert dds.returncode == 0, dds.stderr
        assert json.loads(dds.stdout) == got
    finally:
        stop(pub)


def test_bad_input_on_a_real_graph(graph_env: dict[str, str], start_peer: Start, rclpy_tool: Tool) -> None:
    """Each run fails before it changes anything: all side by side."""
    start_peer("--name", "talker", "--talk", "/chatter")
    compared = (["node", "info", "/nobody"], ["topic", "echo", "/nothing", "--timeout", "1"])
    both_ways = ("source the workspace", "--ros2-backend dds")
    refused = (
        (["topic", "pub", "/chatter", "std_msgs/msg/Nope", "data: 1", "-1"], ("std_msgs/msg/Nope",)),
        (["topic", "pub", "/x", "nothere_msgs/msg/Thing", "a: 1", "-1"], ("'nothere_msgs'", *both_ways)),
        # example_interfaces is not in the peer venv: rclpy cannot import it, the DDS backend has it built in
        (["service", "call", "/add", "example_interfaces/srv/AddTwoInts", "{a: 1}"],
         ("'example_interfaces'", *both_ways)),
        (["action", "send-goal", "/fib", "example_interfaces/action/Fibonacci", "{order: 1}"],
         ("'example_interfaces'", *both_ways)),
        (["param", "get", "/talker", "nope"], ("parameter not set: node /talker has no parameter nope",)),
    )  # fmt: skip
    with ThreadPoolExecutor(max_workers=4) as pool:
        pairs = [(pool.submit(rclpy_tool, *args, timeout=20), pool.submit(rostool, args, graph_env, 20))
                 for args in compared]  # fmt: skip
        runs = [pool.submit(rclpy_tool, *args, timeout=20) for args, _words in refused]
    for args, (mine, theirs) in zip(compared, pairs, strict=True):
        # the DDS backend's line
        assert one_error_line(mine.result()) == one_error_line(theirs.result()), args
    for (_args, words), run in zip(refused, runs, strict=True):
        one_error_line(run.result(), *words)


def test_a_missing_rmw_library_is_one_line(graph_env: dict[str, str], tmp_path: Path, distro: str) -> None:
    """rclpy imports its RMW library (the pip wheels link rmw_fastrtps_cpp): without it on LD_LIBRARY_PATH,
    --ros2-backend rclpy is one line naming the library and the way out, and auto falls back to DDS."""
    python = peer_python(distro)
    lib = python.parent.parent / "lib"
    libs = tmp_path / "libs_without_rmw"
    libs.mkdir()
    for found in lib.glob("*.so*"):
        if not found.name.startswith("librmw_fastrtps_cpp.so"):
            (libs / found.name).symlink_to(found)
    probe = [str(python), "-c", "import os; print(os.environ['LD_LIBRARY_PATH'])"]
    paths = subprocess.run(probe, capture_output=True, text=True, check=True).stdout.strip().split(":")
    env = {**peer_env(graph_env, tmp_path), "_ROS_WHEELS_BOOTSTRAP_COMPLETE": "1",  # the wheels' re-exec
           "LD_LIBRARY_PATH": ":".join(str(libs) if p == str(lib) else p for p in paths)}  # fmt: skip
    command = [str(python), "-m", "rostool", "--ros2-backend", "rclpy", "topic", "list"]
    named = subprocess.run(command, env=env, capture_output=True, text=True, timeout=30)
    one_error_line(named, "RMW_IMPLEMENTATION='rmw_fastrtps_cpp' is not installed", "--ros2-backend dds")
    env.pop("RMW_IMPLEMENTATION")  # the default RMW, which rclpy loads as it imports
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=30)
    line = one_error_line(done, "the RMW library librmw_fastrtps_cpp.so is missing", "--ros2-backend dds")
    assert "https://" not in line  # not rclpy's how-to link
    doctor = subprocess.run([str(python), "-m", "rostool", "doctor", "--json", "--listen", "0"], env=env,
                            capture_output=True,
                            text=True, timeout=30)  # fmt: skip
    report = json.loads(doctor.stdout)["ros2"]
    assert report["backend"] == "dds" and "librmw_fastrtps_cpp.so" in report["reason"]


def test_services_parameters_actions_print_as_the_dds_backend(
    graph_env: dict[str, str], start_peer: Start, rclpy_tool: Tool
) -> None:
    """The same real node seen through rclpy and through rostool's DDS: the same text, GIDs and QoS too.
    The runs only read: side by side, but the two of each param verb one after the other (in_lanes), and
    `service info -v` on its own after them (seen on Kilted: rclpy showed the Fast DDS server's endpoints
    as KEEP_LAST (1), where alone it shows UNKNOWN as the DDS backend does, while another rclpy rostool
    started beside it)."""
    start_peer("--name", "robot", "--service", "/flag", "--params", "--action", "/fib")
    compared = (
        # --timeout: the DDS backend learns Fast DDS's node names on its 3 s heartbeat
        (None, ["service", "list", "-t"]), (None, ["action", "list", "-t"]),
        ("dump", ["param", "dump", "/robot", "--timeout", "5"]),
        ("describe", ["param", "describe", "/robot", "speed", "ids", "--timeout", "5"]),
    )  # fmt: skip

    def run(args: list[str]) -> subprocess.CompletedProcess[str]:
        return rostool(args[1:], graph_env) if args[0] == "dds" else rclpy_tool(*args[1:])

    calls = [(lane, [backend, *args]) for lane, args in compared for backend in ("rclpy", "dds")]
    *results, action_info = in_lanes(run, [*calls, (None, ["rclpy", "action", "info", "/fib", "-t"])])
    alone = ["service", "info", "/flag", "-v"]
    results += [rclpy_tool(*alone), rostool(alone, graph_env)]
    checked = [*(args for _lane, args in compared), alone]
    for args, mine, theirs in zip(checked, results[::2], results[1::2], strict=True):
        assert mine.returncode == 0, (args, mine.stderr)
        assert mine.stdout == theirs.stdout, (args, theirs.stderr)
    # the node by name (the DDS backend may show _NODE_NAME_UNKNOWN_ until Fast DDS names its nodes)
    info = action_info.stdout.splitlines()
    assert info[info.index("Action servers: 1") + 1] == "    /robot [test_msgs/action/Fibonacci]", info


def test_ctrl_c_ends_a_waiting_service_call_quietly(
    graph_env: dict[str, str], tmp_path: Path, distro: str
) -> None:
    args = ["service", "call", "/later", "std_srvs/srv/SetBool", "{data: true}", "--wait"]
    waiting = rostool_rclpy_popen(args, graph_env, tmp_path, distro)
    # in the graph (its participant's sockets are open), so Ctrl+C comes while it waits for the service
    assert wait_until(lambda: bound_addresses(waiting.pid) != [] or waiting.poll() is not None, timeout=30)
    assert waiting.poll() is None, waiting.communicate()
    out, err = stop(waiting, timeout=10)
    assert waiting.returncode == 130, err
    assert "Traceback" not in err and out == ""


def test_a_service_type_rosbags_lacks_comes_from_the_class_rclpy_imports(
    start_peer: Start, rclpy_tool: Tool
) -> None:
    """test_msgs/srv/BasicTypes is in no rosbags store and not built in: described from rclpy's classes, the
    real server echoes the request back field by field."""
    start_peer("--name", "echoer", "--echo-service", "/echo")
    called = rclpy_tool("service", "call", "/echo", "test_msgs/srv/BasicTypes",
                        "{int32_value: 5, string_value: hi, float64_value: 2.5}", "--json")  # fmt: skip
    assert called.returncode == 0, called.stderr
    got = json.loads(called.stdout)
    fields = ("int32_value", "string_value", "float64_value", "bool_value")
    assert [got[f] for f in fields] == [5, "hi", 2.5, False]
