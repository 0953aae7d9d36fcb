"""Bad input to the offline verbs: one line on stderr and a non-zero exit, never a traceback (issue 14).

The rule, per case:
- a failure rostool detects (exit 1, or another non-zero code it chooses): exactly one stderr line,
  starting with `rostool: `;
- a usage error click detects while parsing (exit 2: missing argument, bad option value, unknown option)
  is click's standard block, accepted as is: `Usage: rostool ...`, `Try '... -h' for help.`, a blank
  line and one `Error: ...` line. Nothing else on stderr;
- never `Traceback`, never `internal error` (exit 70), never anything on stdout.
Runs in-process through click's CliRunner (each invocation has its own streams and environment).
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from click.testing import CliRunner

from rostool.cli import root
from tests.test_bag_support import shared

BAG = "{bag}"  # placeholders filled in from the fixture below
MCAP_DIR = "{mcap_dir}"
OUT_EXISTS = "{existing}"
DIRECTORY = "{directory}"
TEXT = "{text}"
MISSING = "{missing}"
BAD_YAML = "{bad_yaml}"
NEW_OUT = "{new_out}"
NO_PARENT = "{no_parent}"

# (id, arguments): every one must fail by the rule above.
CASES: list[tuple[str, list[str]]] = [
    # bag info
    ("info-no-argument", ["bag", "info"]),
    ("info-missing-file", ["bag", "info", MISSING]),
    ("info-empty-directory", ["bag", "info", DIRECTORY]),
    ("info-text-file", ["bag", "info", TEXT]),
    ("info-bad-yaml-no-storage", ["bag", "info", BAD_YAML]),
    ("info-json-and-yaml", ["bag", "info", BAG, "--json", "--yaml"]),
    ("info-unknown-option", ["bag", "info", BAG, "--bogus"]),
    ("info-one-of-several-missing", ["bag", "info", BAG, MISSING]),
    ("info-missing-among-several", ["bag", "info", MCAP_DIR, "--json", MISSING]),
    # bag echo
    ("echo-no-argument", ["bag", "echo"]),
    ("echo-missing-file", ["bag", "echo", MISSING]),
    ("echo-directory-not-a-bag", ["bag", "echo", DIRECTORY]),
    ("echo-text-file", ["bag", "echo", TEXT]),
    ("echo-bad-yaml-no-storage", ["bag", "echo", BAD_YAML]),
    ("echo-unknown-topic", ["bag", "echo", BAG, "/no_such_topic"]),
    ("echo-count-not-a-number", ["bag", "echo", BAG, "-n", "abc"]),
    ("echo-count-zero", ["bag", "echo", BAG, "-n", "0"]),
    ("echo-bad-start", ["bag", "echo", BAG, "--start", "yesterday"]),
    ("echo-bad-filter", ["bag", "echo", BAG, "--filter", "m.linear.x >"]),
    ("echo-unsafe-filter", ["bag", "echo", BAG, "--filter", "__import__('os')"]),
    ("echo-json-and-csv", ["bag", "echo", BAG, "--json", "--csv"]),
    ("echo-csv-several-topics", ["bag", "echo", BAG, "--csv"]),
    ("echo-unknown-distro", ["bag", "echo", MCAP_DIR, "--distro", "rolling-stone"]),
    # bag convert
    ("convert-no-argument", ["bag", "convert"]),
    ("convert-only-source", ["bag", "convert", BAG]),
    ("convert-missing-source", ["bag", "convert", MISSING, NEW_OUT]),
    ("convert-output-exists", ["bag", "convert", BAG, OUT_EXISTS]),
    ("convert-output-is-a-directory", ["bag", "convert", BAG, DIRECTORY]),
    ("convert-output-parent-missing", ["bag", "convert", BAG, NO_PARENT]),
    ("convert-unknown-format", ["bag", "convert", BAG, NEW_OUT, "--format", "zip"]),
    ("convert-unknown-topic", ["bag", "convert", BAG, NEW_OUT, "--topics", "/no_such_topic"]),
    ("convert-text-source", ["bag", "convert", TEXT, NEW_OUT]),
    ("convert-bad-yaml-source", ["bag", "convert", BAD_YAML, NEW_OUT]),
    ("convert-bad-end", ["bag", "convert", BAG, NEW_OUT, "--end", "soon"]),
    ("convert-ros1-and-ros2", ["bag", "convert", BAG, MCAP_DIR, NEW_OUT]),
    # bag filter
    ("filter-no-argument", ["bag", "filter"]),
    ("filter-no-output", ["bag", "filter", BAG]),
    ("filter-missing-source", ["bag", "filter", MISSING, NEW_OUT]),
    ("filter-output-exists", ["bag", "filter", BAG, OUT_EXISTS]),
    ("filter-output-is-a-directory", ["bag", "filter", BAG, DIRECTORY]),
    ("filter-bad-expression", ["bag", "filter", BAG, NEW_OUT, "--filter", "m.linear.x >"]),
    ("filter-unknown-topic", ["bag", "filter", BAG, NEW_OUT, "--topics", "/no_such_topic"]),
    ("filter-directory-source", ["bag", "filter", DIRECTORY, NEW_OUT]),
    ("filter-bad-yaml-source", ["bag", "filter", BAD_YAML, NEW_OUT]),
    # bag reindex
    ("reindex-no-argument", ["bag", "reindex"]),
    ("reindex-missing-file", ["bag", "reindex", MISSING]),
    ("reindex-directory", ["bag", "reindex", DIRECTORY]),
    ("reindex-text-file", ["bag", "reindex", TEXT]),
    ("reindex-rosbag2-directory", ["bag", "reindex", MCAP_DIR]),
    # bag verbs
    ("bag-unknown-verb", ["bag", "inf0", BAG]),
    # msg / srv / cheatsheet (offline)
    ("msg-show-no-argument", ["msg", "show"]),
    ("msg-show-unknown-type", ["msg", "show", "no_such_pkg/NoSuchType"]),
    ("msg-show-not-a-type-name", ["msg", "show", "!!not a type"]),
    ("msg-show-missing-interfaces", ["msg", "show", "std_msgs/String", "--interfaces", MISSING]),
    ("msg-md5-unknown-type", ["msg", "md5", "no_such_pkg/NoSuchType"]),
    ("srv-show-no-argument", ["srv", "show"]),
    ("srv-show-unknown-type", ["srv", "show", "no_such_pkg/NoSuchSrv"]),
    ("srv-show-a-message-type", ["srv", "show", "std_msgs/String"]),
    ("srv-md5-unknown-type", ["srv", "md5", "no_such_pkg/NoSuchSrv"]),
    ("cheatsheet-unknown-section", ["cheatsheet", "--section", "no_such_section"]),
]


@pytest.fixture(scope="module")
def places(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    if not shared("ros1/example.bag").exists():
        pytest.skip("the shared test bags are not there")
    return make_places(tmp_path_factory.mktemp("sweep"))


def make_places(base: Path) -> dict[str, str]:
    """The files and directories the cases name, under `base`."""
    bag = base / "example.bag"
    shutil.copy(shared("ros1/example.bag"), bag)
    mcap_dir = base / "talker_mcap"
    shutil.copytree(shared("ros2/talker_mcap"), mcap_dir)
    existing = base / "existing.mcap"
    existing.write_bytes(b"keep me")
    directory = base / "a_directory"
    directory.mkdir()
    text = base / "notes.txt"
    text.write_text("not a bag\n")
    bad_yaml = base / "bad_yaml"
    bad_yaml.mkdir()
    (base / "out").mkdir()
    (bad_yaml / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  version: [5\n  files: {\n")
    return {
        "bag": str(bag),
        "mcap_dir": str(mcap_dir),
        "existing": str(existing),
        "directory": str(directory),
        "text": str(text),
        "missing": str(base / "no_such.bag"),
        "bad_yaml": str(bad_yaml),
        "new_out": str(base / "out" / "new.mcap"),
        "no_parent": str(base / "no_such_dir" / "deeper" / "out.mcap"),
    }


def _check(result_stderr: str, stdout: str, code: int, exception: BaseException | None) -> str:
    """'' when the outcome follows the rule, else what is wrong."""
    if exception is not None and not isinstance(exception, SystemExit):
        return f"exception escaped: {type(exception).__name__}: {exception}"
    if "Traceback" in result_stderr or "internal error" in result_stderr or code == 70:
        return f"internal error: {result_stderr}"
    if code == 0:
        return "exit 0: the bad input was accepted"
    if stdout.strip():
        return f"stdout not empty: {stdout[:200]!r}"
    lines = result_stderr.rstrip("\n").split("\n")
    if code == 2 and lines[0].startswith("Usage: rostool "):
        if (
            len(lines) == 4
            and lines[1].startswith("Try '")
            and lines[2] == ""
            and lines[3].startswith("Error: ")
        ):
            return ""
        return f"not click's usage block: {lines}"
    if len(lines) != 1 or not lines[0].startswith("rostool: ") or lines[0].startswith("rostool: warning:"):
        return f"not one error line (exit {code}): {lines}"
    return ""


def _fill(args: list[str], places: dict[str, str]) -> list[str]:
    return [arg.format(**places) if arg.startswith("{") else arg for arg in args]


@pytest.mark.parametrize("ros_version", ["1", "2"])
def test_bad_input_gives_one_line(places: dict[str, str], ros_version: str) -> None:
    runner = CliRunner()
    env = {"ROS_VERSION": ros_version, "ROS_MASTER_URI": None, "ROSTOOL_DEBUG": None}
    failures = []
    for name, args in CASES:
        filled = _fill(args, places)
        result = runner.invoke(root, filled, env=env, prog_name="rostool")
        wrong = _check(result.stderr, result.stdout, result.exit_code, result.exception)
        if not wrong and Path(places["new_out"]).exists():
            wrong = "a failed command left its output behind"
        if wrong:
            failures.append(f"{name}: rostool {' '.join(args)}: {wrong}")
    assert not failures, "\n".join(failures)
    # the existing output and the directory were left alone
    assert Path(places["existing"]).read_bytes() == b"keep me"
    assert not any(Path(places["directory"]).iterdir())


def test_the_rule_itself() -> None:
    check: Callable[..., str] = _check
    usage = "Usage: rostool bag info BAG...\nTry 'rostool bag info -h' for help.\n\nError: Missing BAG.\n"
    assert check(usage, "", 2, None) == ""
    assert check("rostool: x.bag: no such file or directory\n", "", 1, None) == ""
    assert "not one error line" in check("rostool: a\nmore\n", "", 1, None)
    assert "internal error" in check("rostool: internal error: KeyError: 'x'\n", "", 70, None)
    assert "exception escaped" in check("", "", 1, KeyError("x"))
    assert "accepted" in check("", "out", 0, None)
