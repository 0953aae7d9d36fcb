"""Damaged bags of every format give a result or one line on stderr, never a traceback (issue 14).

Runs a fixed-seed sample of bench/fuzz_bags.py's cases (mutated copies of the real test bags and of
their metadata.yaml through `bag info`, `bag info --json` and `bag echo --json`) in-process on two
forked workers; the bench script runs 10,000+ and prints the tally.
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest
from click.testing import CliRunner

from rostool.cli import root
from tests.test_bag_support import shared

CASES = 2000  # about 15 s on two idle cores, 35 s on busy ones
SEED = 2024  # not the bench script's seed: the two together cover more


def _load_fuzz() -> ModuleType:
    path = Path(__file__).resolve().parents[1] / "bench" / "fuzz_bags.py"
    spec = importlib.util.spec_from_file_location("fuzz_bags", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_bags"] = module  # dataclasses and pickling look their module up by name
    spec.loader.exec_module(module)
    return module


fuzz = _load_fuzz()


@pytest.fixture(scope="module")
def seeds(tmp_path_factory: pytest.TempPathFactory) -> Iterator[object]:
    if not shared("ros1/example.bag").exists():
        pytest.skip("the shared test bags are not there")
    root_dir = tmp_path_factory.mktemp("fuzz-seeds")
    yield fuzz.make_seeds(root_dir)
    shutil.rmtree(root_dir, ignore_errors=True)


def test_mutated_bags_give_a_result_or_one_line(seeds: object) -> None:
    outcomes = list(fuzz.run_cases(fuzz.plan(CASES, SEED), seeds, workers=2, timeout=30.0))
    assert len(outcomes) == CASES
    bad = sorted((o for o in outcomes if o.kind not in ("clean", "error")), key=lambda o: o.case.number)
    report = "\n".join(f"#{o.case.number} {o.case.fmt} {o.case.command}: {o.kind}: {o.detail}" for o in bad)
    assert not bad, (
        f"{len(bad)} of {CASES} cases broke the one-line rule:\n{report}\n{fuzz.format_tally(outcomes)}"
    )
    table = fuzz.tally(outcomes)
    for fmt in ("bag", "mcap", "db3", "rosbag2", "several"):
        # the mutations really damage inputs, and not every damage is fatal
        assert table[fmt]["error"] > 0 and table[fmt]["clean"] > 0, (fmt, table[fmt])
    # A damaged metadata.yaml never costs the intact storage files beside it.
    assert table["metadata"]["error"] == 0, [o.detail for o in outcomes if o.case.fmt == "metadata"][:5]


def _invoke(args: list[str]) -> tuple[int, str, list[str]]:
    result = CliRunner().invoke(root, args)
    assert not result.exception or isinstance(result.exception, SystemExit), result.exception
    return result.exit_code, result.stdout, result.stderr.splitlines()


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        (b"rosbag2_bagfile_information:\n  version: 5\n  \xff\xfe\n", "not UTF-8 text (byte 0xff at offset"),
        (b"rosbag2_bagfile_information:\n  version: [5\n", "damaged YAML:"),
        (b"rosbag2_bagfile_information:\n  version: \x00\n", "damaged YAML: control characters"),
        (b"just text\n", "not rosbag2 metadata"),
        (b"rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n", "relative_file_paths"),
    ],
)
def test_damaged_metadata_falls_back_to_the_storage_beside_it(
    tmp_path: Path, content: bytes, problem: str
) -> None:
    bag = tmp_path / "talker_mcap"
    shutil.copytree(shared("ros2/talker_mcap"), bag)
    (bag / "metadata.yaml").write_bytes(content)
    code, out, err = _invoke(["bag", "info", "--json", str(bag)])
    assert code == 0
    assert '"messages": 20' in out
    assert len(err) == 1 and err[0].startswith(f"rostool: warning: {bag / 'metadata.yaml'}: "), err
    assert problem in err[0] and err[0].endswith("reading talker.mcap beside it instead"), err
    code, out, err = _invoke(["bag", "echo", "--json", str(bag / "metadata.yaml"), "/topic", "-n", "1"])
    assert (code, out.strip(), len(err)) == (0, '{"data": "Hello, world! 0"}', 1), (out, err)


def test_metadata_listing_a_lost_split_file_reads_the_rest(tmp_path: Path) -> None:
    bag = tmp_path / "split_mcap"
    shutil.copytree(shared("ros2/split_mcap"), bag)
    (bag / "wbag_2.mcap").unlink()
    code, out, err = _invoke(["bag", "info", "--json", str(bag)])
    assert code == 0 and '"files": [' in out
    assert len(err) == 1 and "storage files it lists are missing: wbag_2.mcap" in err[0]
    assert err[0].endswith("reading 4 .mcap files beside it instead")


def test_damaged_metadata_without_storage_is_one_line(tmp_path: Path) -> None:
    bag = tmp_path / "lost"
    bag.mkdir()
    (bag / "metadata.yaml").write_bytes(b"\x89garbage")
    code, out, err = _invoke(["bag", "info", str(bag)])
    assert (code, out) == (1, "")
    assert err == [
        f"rostool: {bag / 'metadata.yaml'}: damaged, not UTF-8 text (byte 0x89 at offset 0); "
        "and no .mcap/.db3 files beside it to read instead"
    ]


def test_several_bags_one_damaged_name_it(tmp_path: Path) -> None:
    good = shared("ros1/no-messages.bag")
    bad = tmp_path / "cut.bag"
    bad.write_bytes(shared("ros1/example.bag").read_bytes()[:50_000])
    code, _out, err = _invoke(["bag", "info", str(good), str(bad)])
    assert code == 1 and len(err) == 1 and err[0].startswith(f"rostool: {bad}: "), err
