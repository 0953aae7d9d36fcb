"""`--force` never deletes an input, nor anything that is not a bag rostool could have written (issue 27);
it still replaces an earlier bag, atomically (no moment without one, no leftover)."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pytest

from tests.support import TESTDATA, ros2_env, rostool
from tests.test_bag_support import write_ros1_bag


def _digests(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def _mcap_counts(path: Path) -> dict[str, int]:
    """Messages per topic, as the mcap library's own reader counts them."""
    from mcap.reader import make_reader

    with path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None
    counts = summary.statistics.channel_message_counts
    return {summary.channels[c].topic: n for c, n in counts.items()}


def _one_line_refusal(stderr: str) -> None:
    assert "Traceback" not in stderr and stderr.count("\n") == 1 and stderr.startswith("rostool: "), stderr


@pytest.mark.parametrize("verb", ["convert", "filter"])
def test_an_output_holding_the_input_is_refused(tmp_path: Path, verb: str) -> None:
    data = tmp_path / "data"
    data.mkdir()
    write_ros1_bag(data / "in.bag")
    nested = data / "sub"
    nested.mkdir()
    (nested / "x.mcap").write_bytes((TESTDATA / "ros2" / "talker_mcap" / "talker.mcap").read_bytes())
    before = _digests(tmp_path)
    for source, target in (
        (data / "in.bag", data),
        (nested / "x.mcap", data),
        (data / "in.bag", data / "in.bag"),
    ):
        result = rostool(["bag", verb, str(source), str(target), "--force"], dict(os.environ))
        assert result.returncode == 1, result.stderr
        _one_line_refusal(result.stderr)
        assert "input" in result.stderr
        assert _digests(tmp_path) == before


def test_force_replaces_only_bags(tmp_path: Path) -> None:
    source = write_ros1_bag(tmp_path / "in.bag")
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "todo.txt").write_text("buy milk")
    text = tmp_path / "report.txt"
    text.write_text("quarterly figures")
    before = _digests(tmp_path)
    for target in (notes, text):
        result = rostool(["bag", "convert", str(source), str(target), "--force"], dict(os.environ))
        assert result.returncode == 1, result.stderr
        _one_line_refusal(result.stderr)
        assert "not a bag" in result.stderr
    assert _digests(tmp_path) == before
    # an earlier bag is replaced, and nothing is left beside it
    old = tmp_path / "old.mcap"
    old.write_bytes((TESTDATA / "ros2" / "talker_mcap" / "talker.mcap").read_bytes())
    done = rostool(["bag", "convert", str(source), str(old), "--force"], dict(os.environ))
    assert done.returncode == 0, done.stderr
    assert _mcap_counts(old) == {"/chatter": 30, "/cmd_vel": 30, "/tf": 30}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.bag", "notes", "old.mcap", "report.txt"]
    rebuilt = tmp_path / "rosbag2_dir"
    assert rostool(["bag", "convert", str(source), str(rebuilt)], dict(os.environ)).returncode == 0
    again = rostool(["bag", "convert", str(source), str(rebuilt), "--force", "--topics", "/chatter"],
                    dict(os.environ))  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert _mcap_counts(next(rebuilt.glob("*.mcap"))) == {"/chatter": 30}


def test_ros2_record_force_keeps_unrelated_files(tmp_path: Path) -> None:
    out = tmp_path / "mine"
    out.mkdir()
    (out / "calibration.yaml").write_text("k: 1")
    (out / "metadata.yaml").write_text("not even a bag")
    before = _digests(tmp_path)
    result = rostool(["--ros2", "bag", "record", "-a", "-o", str(out), "--force"], ros2_env())
    assert result.returncode == 1, result.stderr
    _one_line_refusal(result.stderr)
    assert "not a bag" in result.stderr
    assert _digests(tmp_path) == before
