"""The root command: lazy start-up, version selection, one-line errors, --help examples everywhere."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import click
import pytest

from rostool.cli import COMMANDS, root
from rostool.commands._common import _load, _spec_exists
from rostool.graph import select_ros_version
from tests.support import free_port, ros2_env

HEAVY = ("rosbags", "cyclonedds", "yaml", "rich", "numpy", "mcap", "rostool.graph", "rostool.bag")


def test_root_help_imports_no_ros_machinery() -> None:
    probe = (
        "import sys, io, contextlib\n"
        "from rostool.cli import root\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        root.main(['--help'])\n    except SystemExit:\n        pass\n"
        f"print([m for m in {HEAVY!r} if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def _walk(command: click.Command, path: tuple[str, ...]) -> list[tuple[tuple[str, ...], click.Command]]:
    found = [(path, command)]
    if isinstance(command, click.Group):
        ctx = click.Context(command)
        for name in command.list_commands(ctx):
            sub = command.get_command(ctx, name)
            assert sub is not None
            found += _walk(sub, (*path, name))
        for name, spec in getattr(command, "ros2_forms", {}).items():
            if _spec_exists(spec):  # the ROS 2 form of a verb (e.g. bag record): its own --help
                found += _walk(_load(spec), (*path, name))
    return found


def test_every_command_help_has_an_example() -> None:
    commands = _walk(root, ())
    assert {path[0] for path, _ in commands if path} == set(COMMANDS)
    for path, command in commands:
        text = (command.help or "") + (command.epilog or "")
        assert "Example" in text or "example" in text, f"rostool {' '.join(path)} --help has no example"


@pytest.mark.parametrize(
    ("explicit", "env", "expected"),
    [
        (1, {"ROS_VERSION": "2"}, 1),
        (2, {"ROS_MASTER_URI": "http://127.0.0.1:1"}, 2),
        (None, {"ROS_VERSION": "2", "ROS_MASTER_URI": "http://127.0.0.1:1"}, 2),
        (None, {"ROS_MASTER_URI": "http://127.0.0.1:1"}, 1),
    ],
)
def test_version_selection(
    explicit: int | None, env: dict[str, str], expected: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    for var in ("ROS_VERSION", "ROS_MASTER_URI"):
        monkeypatch.delenv(var, raising=False)
    for var, value in env.items():
        monkeypatch.setenv(var, value)
    assert select_ros_version(explicit) == expected


def test_malformed_master_uri_is_the_users_error() -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["ROS_MASTER_URI"] = "http://127.0.0.1:notaport"
    command = [sys.executable, "-m", "rostool", "topic", "list"]
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=30)
    assert result.returncode != 0 and "Traceback" not in result.stderr
    assert result.stderr.strip().splitlines() == [
        "rostool: ROS_MASTER_URI='http://127.0.0.1:notaport' is not a master URI like http://localhost:11311"
    ]


def test_unknown_command_is_a_usage_error() -> None:
    env = {**os.environ, "ROS_MASTER_URI": f"http://127.0.0.1:{free_port()}"}
    command = [sys.executable, "-m", "rostool", "tpoic"]
    result = subprocess.run(command, env=env, capture_output=True, text=True)
    assert result.returncode == 2 and "No such command 'tpoic'" in result.stderr


@pytest.mark.parametrize("moment", [0.03, 0.06, 0.1, 0.15, 0.2, 0.3, 0.5, 0.8])
def test_ctrl_c_while_starting_is_quiet(moment: float, tmp_path: Path) -> None:
    """SIGINT at any moment of start-up (imports, the graph opening) ends with 130 and no traceback."""
    import signal
    import time

    rostool = Path(sys.executable).with_name("rostool")
    process = subprocess.Popen(
        [str(rostool), "--ros2", "--ros2-backend", "dds", "bag", "record", "/nothing", "-O", "x.mcap"],
        cwd=tmp_path, env={**ros2_env(), "PYTHONFAULTHANDLER": "1"},  # a hang dumps its threads on SIGABRT
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    time.sleep(moment)
    process.send_signal(signal.SIGINT)
    try:
        _out, err = process.communicate(timeout=30)
    except subprocess.TimeoutExpired:  # seen under load: say where it hung
        process.send_signal(signal.SIGABRT)
        _out, err = process.communicate(timeout=30)
        pytest.fail(f"still running 30 s after SIGINT at {moment} s; its threads:\n{err[-4000:]}")
    # Before any rostool code runs: the signal came before Python installed its handler (the process dies
    # of it: rostool never restores SIGINT's default), or during one of Python's own init stages (its fatal
    # error names them: init_import_site, init_sys_streams, ...)
    if process.returncode == -signal.SIGINT or "Fatal Python error: init_" in err:
        pytest.skip("the interrupt reached Python's own start-up, before any rostool code runs")
    assert "Traceback" not in err and "internal error" not in err, err
    assert process.returncode in (0, 130), (process.returncode, err)
    assert not list(tmp_path.glob("*.active")), "an interrupted recorder left a .active"
