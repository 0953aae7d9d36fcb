"""How a finished verb ends (rostool/_entry.py): with `os._exit` after flushing instead of the interpreter's
finalization, yet with the same exit codes, every line printed and every file written complete."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

from rostool._entry import _exit_code
from tests.support import ros2_env, rostool
from tests.test_issue25_services import write_strings_bag

COUNT = 5000  # lines well past a pipe's and Python's buffers


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("exit") / "strings"
    write_strings_bag(path, COUNT)
    return path


def test_every_line_printed_reaches_the_pipe(bag: Path) -> None:
    done = rostool(["bag", "echo", str(bag), "--json"], ros2_env(), timeout=120)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == COUNT and '"n 0"' in lines[0] and f'"n {COUNT - 1}"' in lines[-1]


def test_files_written_by_verbs_are_complete(bag: Path, tmp_path: Path) -> None:
    from rosbags.highlevel import AnyReader

    converted = tmp_path / "strings.bag"
    done = rostool(["bag", "convert", str(bag), str(converted)], ros2_env(), timeout=120)
    assert done.returncode == 0, done.stderr
    with AnyReader([converted]) as reader:  # rosbags, not rostool's reader
        texts = [reader.deserialize(data, c.msgtype).data for c, _t, data in reader.messages()]
    assert texts == [f"n {n}" for n in range(COUNT)]

    tables = tmp_path / "tables"
    done = rostool(["bag", "export", str(bag), "--format", "csv", "-o", str(tables)], ros2_env(), timeout=120)
    assert done.returncode == 0, done.stderr
    with open(tables / "chatter.csv", newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["data"] for row in rows] == [f"n {n}" for n in range(COUNT)]


def test_exit_codes_stay_exact(tmp_path: Path) -> None:
    env = ros2_env()
    ok = rostool(["--version"], env)
    assert ok.returncode == 0 and "rostool, version" in ok.stdout
    usage = rostool(["tpoic"], env)
    assert usage.returncode == 2 and "No such command 'tpoic'" in usage.stderr
    missing = rostool(["bag", "info", str(tmp_path / "absent.bag")], env)
    assert missing.returncode == 1 and missing.stderr.count("\n") == 1 and "rostool:" in missing.stderr


def test_a_closed_pipe_ends_quietly(bag: Path) -> None:
    process = subprocess.Popen([sys.executable, "-m", "rostool", "bag", "echo", str(bag)], env=ros2_env(),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    assert process.stdout is not None and process.stderr is not None
    first = process.stdout.readline()
    process.stdout.close()  # as `| head -1` does
    err = process.stderr.read().decode()
    assert process.wait(timeout=60) == 0 and first and "Traceback" not in err and "Exception" not in err


def test_a_message_given_to_sys_exit_ends_with_1(capsys: pytest.CaptureFixture[str]) -> None:
    assert (_exit_code(None), _exit_code(0), _exit_code(3), _exit_code(130)) == (0, 0, 3, 130)
    assert _exit_code("rostool: gone") == 1
    assert capsys.readouterr().err == "rostool: gone\n"
