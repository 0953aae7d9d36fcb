# ruff: noqa: E501  (expected ros2cli lines are kept whole)
"""ros2cli's own ros2param test cases, run against rostool and real rclpy peers (Jazzy).

Command lines and expected output lines are those of ros2cli's tests (ros2param/test/test_cli.py,
test_verb_list.py, test_verb_get.py, test_verb_set.py, test_verb_dump.py, test_verb_load.py,
test_timeout_alias.py), taken as facts; the graph is rebuilt from tests/rclpy_peer.py: /param_node and
/_hidden_param_node declare test/param_node.py's parameters, /foo/test_node test/fixtures/parameter_node.py's.
Where rclpy of Jazzy differs from the ros2cli test's era, the case says so next to its expectation.

The cases ask as users run rostool, through a warm graph daemon of the test's own (node names from it, the
parameter services from the verb's own discovery); the "node not found" cases ask directly
(ROSTOOL_NO_DAEMON=1), as do test_ros2_fastdds_rpc.py's test_parameters_of_a_real_node on both backends.
Cases that change no parameter run side by side (`Early`, which says how).
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.ros2_peers import RclpyPeer, StartPeer, WarmDaemon
from tests.support import rostool, wait_until
from tests.test_ros2cli_forms import Cases

GET_VERB_PARAM_VALUES = {
    "bool_param": "Boolean value is: True\n",
    "int_param": "Integer value is: 42\n",
    "double_param": "Double value is: 1.23\n",
    "str_param": "String value is: Hello World\n",
    "byte_array": "Byte values are: [b'p', b'v']\n",
    "bool_array": "Boolean values are: [True, False, True]\n",
    "int_array": "Integer values are: [1, 2, 3]\n",  # as Jazzy's ros2 param get prints them
    "double_array": "Double values are: [1.0, 2.0, 3.0]\n",
    "str_array": "String values are: ['Hello', 'World']\n",
    "parameter_with_no_value": "Parameter not set.\n",
}
DESCRIBE_TYPES = {
    "bool_param": "boolean", "int_param": "integer", "double_param": "double", "str_param": "string",
    "byte_array": "byte array", "bool_array": "boolean array", "int_array": "integer array",
    "double_array": "double array", "str_array": "string array", "parameter_with_no_value": "not set",
}  # fmt: skip
# ros2cli's PARAM_NODE_PARAMETER_LIST; rclpy since Jazzy also declares start_type_description_service
PARAM_NODE_LIST = "".join(
    f"  {n}\n" for n in sorted([*DESCRIBE_TYPES, "start_type_description_service", "use_sim_time"])
)
TEST_NODE = "/foo/test_node"
INPUT_PARAMETER_FILE = (
    f"{TEST_NODE}:\n  ros__parameters:\n    bool_array_param:\n    - true\n    - false\n    - false\n"
    "    bool_param: false\n    double_array_param:\n    - 2.125\n    - 1.25\n    - 2.5\n    double_param: 1.3\n"
    "    foo:\n      bar:\n        str_param: foo_bar\n      str_param: foobar\n    int_array_param:\n    - 42\n"
    "    - 3\n    - 3\n    int_param: -42\n    str_array_param:\n    - a_foo\n    - a_bar\n    - baz\n"
    "    str_param: Bye World\n    use_sim_time: false\n"
)
INPUT_WILDCARD_PARAMETER_FILE = "/**:\n  ros__parameters:\n    str_param: Wildcard\n    int_param: 12345\n"
INPUT_NODE_OVERLAY_PARAMETER_FILE = f"{TEST_NODE}:\n  ros__parameters:\n    str_param: Override\n"
TYPE_SERVICE_LINE = "    start_type_description_service: true\n"


def param(env: dict[str, str], *args: str) -> Any:
    return rostool(["--ros2", "param", *args], env, timeout=40)


class Early:
    """`param` runs started together and read where the test checks them: each waits for discovery (a node
    that is not there, the whole settle window), so side by side the test waits about once per round. Only
    cases that change no parameter. The runs that call one node's parameter services go in one of `lanes`,
    one after the other: rostool's DDS client of a Fast DDS server takes the first reply after its request,
    which may be another client's if two call that server at once (rostool/graph/ros2/services.py). Lanes
    run side by side, each of `calls` is a lane of its own, and `last` (runs that call every node) runs
    after every lane."""

    Call = tuple[str, ...]

    def __init__(
        self,
        env: dict[str, str],
        *calls: Call,
        lanes: Sequence[Sequence[Call]] = (),
        last: Sequence[Call] = (),
        workers: int = 3,
    ) -> None:
        every = [*((call,) for call in calls), *lanes]
        self._results: dict[Early.Call, Any] = {}
        pool = ThreadPoolExecutor(max_workers=workers)
        running = [pool.submit(self._run, env, lane) for lane in every]
        after = pool.submit(self._after, env, running, last)
        self._started = {call: future for lane, future in zip(every, running, strict=True) for call in lane}
        self._started.update({call: after for call in last})
        pool.shutdown(wait=False)

    def _run(self, env: dict[str, str], lane: Sequence[Call]) -> None:
        for call in lane:
            self._results[call] = param(env, *call)

    def _after(self, env: dict[str, str], running: list[Future[None]], last: Sequence[Call]) -> None:
        for lane in running:
            lane.result()
        self._run(env, last)

    def __call__(self, *call: str) -> Any:
        self._started[call].result(timeout=300)
        return self._results[call]


def not_found(result: Any) -> bool:
    return result.returncode == 1 and "Node not found" in result.stderr and result.stdout == ""


@pytest.fixture
def param_graph(warm_daemon: WarmDaemon, start_peer: StartPeer) -> dict[str, RclpyPeer]:
    """The three parameter nodes, started side by side; the test's warm daemon knows all three."""
    roles = {
        "param_node": ["--name", "param_node", "--ros2cli-params", "param_node"],
        "hidden": ["--name", "_hidden_param_node", "--ros2cli-params", "param_node"],
        "test_node": ["--name", "test_node", "--namespace", "/foo", "--ros2cli-params", "parameter_node"],
    }
    peers = dict(zip(roles, start_peer.together(*roles.values()), strict=True))
    warm_daemon.ready()
    assert wait_until(lambda: warm_daemon.graph_size()["nodes"] == len(peers), timeout=20)
    return peers


@pytest.mark.parametrize("distro", ["jazzy"])  # the parameter services are rclpy's, the same in Kilted
def test_param_get_list_describe(
    graph_env: dict[str, str], warm_daemon: WarmDaemon, param_graph: dict[str, RclpyPeer]
) -> None:
    """Every case here only reads: side by side (see Early), the node-not-found ones directly."""
    c = Cases()
    direct = Early(graph_env, ("get", "/foo/nonexistent_node", "test_param"), ("list", "/nonexistent_node"),
                   ("list", "/_hidden_param_node"), ("describe", "/foo/nonexistent_node", "int_param"),
                   ("list", "invalid_node"), ("list", "invalid_ns/test_node"))  # fmt: skip
    served = Early(
        warm_daemon.env,
        lanes=[
            [
                *(("get", "/param_node", key) for key in GET_VERB_PARAM_VALUES),
                *(
                    ("get", "/param_node", key, "--hide-type")
                    for key in ("int_array", "parameter_with_no_value")
                ),
                ("list", "/param_node"),
                ("describe", "/param_node", *DESCRIBE_TYPES),
            ],
            [
                ("get", "/_hidden_param_node", "test_param"),
                ("get", "/_hidden_param_node", "int_param", "--include-hidden-nodes"),
                ("list", "/_hidden_param_node", "--include-hidden-nodes"),
            ],
            [
                ("list", "--param-prefixes=foo", TEST_NODE),
                ("list", TEST_NODE, "--service-timeout", "10"),
                ("list", TEST_NODE, "--service-timeout", "10", "--filter", "bool.*"),
                ("list", "-t", TEST_NODE, "--timeout", "2.5"),
            ],
        ],
        last=[("get", "use_sim_time"), ("get", "use_sim_time", "--hide-type"), ("get", "nonexistent_param")],
        workers=4,
    )
    for key, expected in GET_VERB_PARAM_VALUES.items():
        got = served("get", "/param_node", key)
        c.check(f"test_get_verb[{key}]", got.returncode == 0 and got.stdout == expected, got)
    for key in ("int_array", "parameter_with_no_value"):
        got = served("get", "/param_node", key, "--hide-type")
        shown = (
            GET_VERB_PARAM_VALUES[key].split(":")[1].strip() if ":" in GET_VERB_PARAM_VALUES[key] else "None"
        )
        c.check(f"test_get_verb_hide_type[{key}]", got.returncode == 0 and got.stdout == shown + "\n", got)
    c.check("test_get_nonexistent_node", not_found(direct("get", "/foo/nonexistent_node", "test_param")))
    c.check(
        "test_get_hidden_node_with_no_hidden_argument",
        not_found(served("get", "/_hidden_param_node", "test_param")),
    )
    got = served("get", "/_hidden_param_node", "int_param", "--include-hidden-nodes")
    c.check("test_get_hidden_node_with_hidden_argument", got.stdout == "Integer value is: 42\n", got)
    got = served("list", "/param_node")
    c.check("test_list_existing_node", got.returncode == 0 and got.stdout == PARAM_NODE_LIST, got)
    c.check("test_list_nonexistent_node", not_found(direct("list", "/nonexistent_node")))
    c.check("test_list_hidden_existing_node_no_hidden_flag", not_found(direct("list", "/_hidden_param_node")))
    got = served("list", "/_hidden_param_node", "--include-hidden-nodes")
    c.check("test_list_hidden_existing_node_hidden_flag", got.stdout == PARAM_NODE_LIST, got)
    # ros2cli's case lists 'bool' for --param-prefixes=bool; rclpy of Jazzy matches PREFIX or PREFIX.* only
    got = served("list", "--param-prefixes=foo", TEST_NODE)
    c.check(
        "test_list_existing_node_bool_prefix (prefix foo)",
        got.stdout == "  foo.bar.str_param\n  foo.str_param\n",
        got,
    )
    got = served("describe", "/param_node", *DESCRIBE_TYPES)
    expected = "".join(
        f"Parameter name: {k}\n  Type: {t}\n  Constraints:\n" for k, t in DESCRIBE_TYPES.items()
    )
    c.check("test_describe_existing_node_all_params", got.stdout == expected, got)
    c.check(
        "test_describe_nonexistent_node",
        not_found(direct("describe", "/foo/nonexistent_node", "int_param")),
    )
    c.check("test_verb_list_invalid_node", not_found(direct("list", "invalid_node"))
            and not_found(direct("list", "invalid_ns/test_node")))  # fmt: skip
    got = served("list", TEST_NODE, "--service-timeout", "10").stdout.splitlines()
    wanted = ["  bool_array_param", "  bool_param", "  double_array_param", "  double_param", "  foo.bar.str_param",
              "  foo.str_param", "  int_array_param", "  int_param", "  start_type_description_service",
              "  str_array_param", "  str_param", "  use_sim_time"]  # fmt: skip
    c.check("test_verb_list", got == wanted, got)
    got = served("list", TEST_NODE, "--service-timeout", "10", "--filter", "bool.*")
    c.check("test_verb_list_filter", got.stdout == "  bool_array_param\n  bool_param\n", got)
    got = served("list", "-t", TEST_NODE, "--timeout", "2.5")
    c.check("test_timeout_alias (--timeout) and --param-type", got.returncode == 0
            and "  int_param (type: integer)" in got.stdout.splitlines(), got)  # fmt: skip
    got = served("get", "use_sim_time")
    c.check("test_verb_get_all_nodes", all(n in got.stdout for n in ("/param_node", TEST_NODE))
            and "Boolean value is:" in got.stdout and "/_hidden_param_node" not in got.stdout, got)  # fmt: skip
    got = served("get", "use_sim_time", "--hide-type")
    c.check(
        "test_verb_get_all_nodes_hide_type",
        TEST_NODE in got.stdout and "Boolean value is:" not in got.stdout,
        got,
    )
    got = served("get", "nonexistent_param")
    c.check("test_verb_get_all_nodes_nonexistent_param", got.returncode == 0
            and "Parameter 'nonexistent_param' not set on any node" in got.stdout, got)  # fmt: skip
    c.done()


@pytest.mark.parametrize("distro", ["jazzy"])
def test_param_set_dump_load(
    graph_env: dict[str, str], warm_daemon: WarmDaemon, param_graph: dict[str, RclpyPeer], tmp_path: Path
) -> None:
    """One case after the other (they change /foo/test_node's parameters and read them back), but the
    node-not-found ones, directly and side by side."""
    env, c = warm_daemon.env, Cases()
    early = Early(graph_env, ("set", "/nonexistent_node", "bool_param", "true"), ("dump", "invalid_node"),
                  ("dump", "invalid_ns/test_node"))  # fmt: skip
    got = param(env, "set", TEST_NODE, "bool_param", "false")
    c.check(
        "test_verb_set_single_param_bool",
        got.returncode == 0 and got.stdout == "Set parameter successful\n",
        got,
    )
    c.check(
        "test_verb_set_node_not_found",
        not_found(early("set", "/nonexistent_node", "bool_param", "true")),
    )
    got = param(env, "set", TEST_NODE, "bool_param", "false", "int_param", "7")
    c.check("test_verb_set_multiple_params", got.returncode == 0 and "bool_param: Set parameter successful" in got.stdout
            and "int_param: Set parameter successful" in got.stdout, got)  # fmt: skip
    got = param(env, "set", TEST_NODE, "bool_param", "false", "int_param")
    c.check("test_verb_set_odd_number_of_args", got.returncode != 0 and "name/value pairs" in got.stderr, got)
    got = param(env, "set", TEST_NODE, "bool_param", "true", "nonexistent_param", "some_value")
    # ros2cli exits 0 here; rostool exits 1 when any parameter was refused (its rule for failures)
    c.check("test_verb_set_multiple_params_one_nonexistent (exit 1 by rule)", got.returncode == 1
            and "bool_param: Set parameter successful" in got.stdout
            and "nonexistent_param: Setting parameter failed" in got.stderr, got)  # fmt: skip

    c.check("test_verb_dump_invalid_node", not_found(early("dump", "invalid_node"))
            and not_found(early("dump", "invalid_ns/test_node")))  # fmt: skip
    got = param(env, "dump", "foo/test_node", "--output-dir", "invalid_path")
    c.check(
        "test_verb_dump_invalid_path",
        got.returncode == 1 and "'invalid_path' is not a valid directory." in got.stderr,
        got,
    )
    load = tmp_path / "params.yaml"
    load.write_text(INPUT_PARAMETER_FILE)
    got = param(env, "load", TEST_NODE, str(load))
    c.check("test_verb_load", got.returncode == 0, got)
    dumped = param(env, "dump", TEST_NODE, "--print")
    c.check("test_verb_load (dump --print equals the file; + rclpy's start_type_description_service)",
            dumped.stdout.replace(TYPE_SERVICE_LINE, "") == INPUT_PARAMETER_FILE + "\n", dumped)  # fmt: skip
    out = tmp_path / "out"
    out.mkdir()
    got = param(env, "dump", TEST_NODE, "--output-dir", str(out))
    written = out / "foo__test_node.yaml"
    c.check("test_verb_dump (--output-dir writes foo__test_node.yaml)", got.returncode == 0 and written.exists()
            and written.read_text().replace(TYPE_SERVICE_LINE, "") == INPUT_PARAMETER_FILE, got)  # fmt: skip
    printed = tmp_path / "printed"
    printed.mkdir()
    got = param(env, "dump", "foo/test_node", "--output-dir", str(printed), "--print")
    c.check("test_verb_dump_print (--print preempts --output-dir)", got.stdout.strip() == dumped.stdout.strip()
            and not any(printed.iterdir()), got)  # fmt: skip
    got = param(env, "load")
    c.check("test_verb_load_missing_args", got.returncode != 0 and "Missing argument" in got.stderr, got)
    c.check("test_verb_load_invalid_node", not_found(param(env, "load", "invalid_node", str(load))))
    got = param(env, "load", TEST_NODE, "invalid_path")
    c.check(
        "test_verb_load_invalid_path", got.returncode != 0 and "No such file or directory" in got.stderr, got
    )
    load.write_text(INPUT_WILDCARD_PARAMETER_FILE)
    got = param(env, "load", TEST_NODE, str(load), "--no-use-wildcard")
    c.check("test_verb_load_wildcard (only '/**' without the wildcard; rostool's words)", got.returncode != 0
            and f"does not contain any valid parameters for {TEST_NODE}" in got.stderr, got)  # fmt: skip
    got = param(env, "load", TEST_NODE, str(load), "--use-wildcard")
    values = yaml.safe_load(param(env, "dump", TEST_NODE, "--print").stdout)[TEST_NODE]["ros__parameters"]
    c.check("test_verb_load_wildcard (--use-wildcard)", got.returncode == 0 and values["str_param"] == "Wildcard"
            and values["int_param"] == 12345, (got, values))  # fmt: skip
    load.write_text(INPUT_WILDCARD_PARAMETER_FILE + "\n" + INPUT_NODE_OVERLAY_PARAMETER_FILE)
    got = param(env, "load", TEST_NODE, str(load))
    values = yaml.safe_load(param(env, "dump", TEST_NODE, "--print").stdout)[TEST_NODE]["ros__parameters"]
    c.check("test_verb_load_wildcard (the node's section wins)", got.returncode == 0
            and values["str_param"] == "Override" and values["int_param"] == 12345, (got, values))  # fmt: skip
    for args in (
        ["list", "--no-daemon", "--spin-time", "1", "-s"],
        ["get", "--no-daemon", TEST_NODE, "int_param"],
    ):
        got = param(env, *args)
        c.check(f"accepted and ignored: param {' '.join(args)}", got.returncode == 0, got)
    c.done()
