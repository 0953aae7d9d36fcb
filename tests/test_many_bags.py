"""Several bags at once: a directory of bags through info/echo/export/convert/filter, in parallel (-j)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.support import rostool
from tests.test_bag_support import copy_shared, env, true_counts, write_ros1_bag

pq = pytest.importorskip("pyarrow.parquet")


@pytest.fixture
def fleet(tmp_path: Path) -> Path:
    """fleet/a.bag, fleet/b.bag, fleet/sub/c.bag (ROS 1) and fleet/talker_mcap (a rosbag2 directory)."""
    root = tmp_path / "fleet"
    (root / "sub").mkdir(parents=True)
    write_ros1_bag(root / "a.bag", count=90)
    write_ros1_bag(root / "b.bag", count=60)
    write_ros1_bag(root / "sub" / "c.bag", count=30)
    copy_shared("ros2/talker_mcap", root)
    return root


NAMES = ["a", "b", "sub__c", "talker_mcap"]


def run_ok(args: list[str]) -> str:
    result = rostool(args, env(), timeout=180)
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_export_directory_is_a_dataset_partitioned_by_bag(fleet: Path, tmp_path: Path) -> None:
    duckdb = pytest.importorskip("duckdb")
    out = tmp_path / "out"
    run_ok(["bag", "export", str(fleet), "-o", str(out), "-j", "2"])
    assert sorted(p.name for p in (out / "cmd_vel").iterdir()) == ["bag=a", "bag=b", "bag=sub__c"]
    assert (out / "topic" / "bag=talker_mcap" / "part-0.parquet").is_file()
    db = duckdb.connect()
    query = (
        "SELECT bag, count(*) FROM read_parquet('{}/*/*.parquet', hive_partitioning=true) "
        "GROUP BY bag ORDER BY bag"
    )
    counts = dict(db.execute(query.format(out / "cmd_vel")).fetchall())
    expected = {name: true_counts(fleet / f"{name.replace('__', '/')}.bag")["/cmd_vel"] for name in NAMES[:3]}
    assert counts == expected == {"a": 30, "b": 20, "sub__c": 10}
    types = dict(
        (row[0], row[1])
        for row in db.execute(
            f"DESCRIBE SELECT * FROM read_parquet('{out / 'cmd_vel'}/*/*.parquet', hive_partitioning=true)"
        ).fetchall()
    )
    assert types["t"] == "BIGINT" and types["linear.x"] == "DOUBLE" and types["bag"] == "VARCHAR"
    rows = db.execute(
        f"SELECT data, t FROM read_parquet('{out / 'chatter'}/*/*.parquet', hive_partitioning=true) "
        "WHERE bag = 'b' ORDER BY t LIMIT 2"
    ).fetchall()
    assert [row[0] for row in rows] == ["hello 0", "hello 3"]


def tree(root: Path) -> dict[str, object]:
    """Every file under `root`: Parquet as its table (bytes may differ in metadata), others as bytes."""
    files: dict[str, object] = {}
    for path in sorted(root.rglob("*")):
        if path.is_file():
            name = str(path.relative_to(root))
            files[name] = pq.read_table(path).to_pylist() if path.suffix == ".parquet" else path.read_bytes()
    return files


def test_parallel_output_equals_serial(fleet: Path, tmp_path: Path) -> None:
    for fmt in ("parquet", "csv"):
        one, two = tmp_path / f"{fmt}1", tmp_path / f"{fmt}2"
        run_ok(["bag", "export", str(fleet), "--format", fmt, "-o", str(one), "-j", "1"])
        run_ok(["bag", "export", str(fleet), "--format", fmt, "-o", str(two), "-j", "2"])
        assert tree(one) == tree(two) and len(tree(one)) == 3 * 3 + 3  # 3 topics in each bag
    serial = run_ok(["bag", "echo", str(fleet), "--json", "-j", "1"])
    parallel = run_ok(["bag", "echo", str(fleet), "--json", "-j", "2"])
    assert serial == parallel
    lines = [json.loads(line) for line in serial.splitlines()]
    bags = [line["bag"] for line in lines]
    assert bags == sorted(bags, key=NAMES.index)  # bag after bag, in sorted order
    assert [bags.count(name) for name in NAMES] == [90, 60, 30, 20]
    info1 = json.loads(run_ok(["bag", "info", str(fleet), "--json", "-j", "1"]))
    info2 = json.loads(run_ok(["bag", "info", str(fleet), "--json", "-j", "2"]))
    assert info1 == info2 and [i["messages"] for i in info1] == [90, 60, 30, 20]


def test_a_rosbag2_directory_is_one_bag(tmp_path: Path) -> None:
    split = copy_shared("ros2/split_mcap", tmp_path)
    info = json.loads(run_ok(["bag", "info", str(split), "--json"]))
    assert isinstance(info, dict) and info["messages"] == 6074
    out = tmp_path / "out"
    run_ok(["bag", "export", str(split), "-o", str(out), "--topics", "AAA"])
    assert [p.name for p in out.iterdir()] == ["AAA.parquet"]  # one bag: no partitions


def test_several_bags_named_one_by_one(fleet: Path) -> None:
    text = run_ok(
        ["bag", "echo", str(fleet / "b.bag"), str(fleet / "a.bag"), "/chatter", "--json", "-n", "1"]
    )
    lines = [json.loads(line) for line in text.splitlines()]
    assert [(line["bag"], line["topic"], line["msg"]["data"]) for line in lines] == [
        ("b", "/chatter", "hello 0"),
        ("a", "/chatter", "hello 0"),
    ]
    yaml_text = run_ok(["bag", "echo", str(fleet / "a.bag"), str(fleet / "b.bag"), "/cmd_vel", "-n", "1"])
    assert yaml_text.splitlines()[0] == f"# bag: {fleet / 'a.bag'}"
    assert f"# bag: {fleet / 'b.bag'}" in yaml_text.splitlines()


def test_a_broken_bag_among_several(fleet: Path, tmp_path: Path) -> None:
    (fleet / "broken.bag").write_text("not a bag\n")
    out = tmp_path / "out"
    result = rostool(["bag", "export", str(fleet), "-o", str(out), "-j", "2"], env(), timeout=180)
    assert result.returncode == 1 and result.stderr.count("\n") == 1
    assert f"{fleet / 'broken.bag'}: not a bag" in result.stderr
    going = rostool(
        ["bag", "export", str(fleet), "-o", str(out), "-j", "2", "--keep-going"], env(), timeout=180
    )
    assert going.returncode == 1
    assert going.stderr.splitlines() == [
        f"rostool: warning: skipped {fleet / 'broken.bag'}: {fleet / 'broken.bag'}: not a bag "
        "(expected a ROS 1 .bag, an .mcap or .db3 file, or a rosbag2 dir)",
        "rostool: 1 of 5 bags failed (see the warnings above)",
    ]
    assert sorted(p.name for p in (out / "cmd_vel").iterdir()) == ["bag=a", "bag=b", "bag=sub__c"]
    assert not list(out.rglob("*.partial"))


def test_convert_and_filter_each_bag_of_a_directory(fleet: Path, tmp_path: Path) -> None:
    converted = tmp_path / "mcap"
    result = rostool(["bag", "convert", str(fleet), str(converted), "--format", "mcap", "-j", "2"], env())
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in converted.iterdir()) == [f"{name}.mcap" for name in NAMES]
    counts = [i["messages"] for i in json.loads(run_ok(["bag", "info", str(converted), "--json"]))]
    assert counts == [90, 60, 30, 20]
    filtered = tmp_path / "filtered"
    result = rostool(
        ["bag", "filter", str(fleet), str(filtered), "--filter", 'topic == "/chatter"', "-j", "2"], env()
    )
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in filtered.iterdir()) == ["a.bag", "b.bag", "sub__c.bag", "talker_mcap"]
    chatter = [i["messages"] for i in json.loads(run_ok(["bag", "info", str(filtered), "--json"]))]
    assert chatter == [30, 20, 10, 0]


def test_topics_some_bags_lack(fleet: Path, tmp_path: Path) -> None:
    """In a fleet a named topic may be missing from some bags: they contribute nothing, no error."""
    out = tmp_path / "filtered"
    result = rostool(["bag", "filter", str(fleet), str(out), "--topics", "/topic,/cmd_vel", "-j", "1"], env())
    assert result.returncode == 0, result.stderr
    counts = {
        Path(i["path"]).name: i["messages"] for i in json.loads(run_ok(["bag", "info", str(out), "--json"]))
    }
    assert counts == {"a.bag": 30, "b.bag": 20, "sub__c.bag": 10, "talker_mcap": 10}
    tables = tmp_path / "tables"
    run_ok(["bag", "export", str(fleet), "--topics", "/topic", "-o", str(tables), "-j", "1"])
    assert [str(p.relative_to(tables)) for p in tables.rglob("*.parquet")] == [
        "topic/bag=talker_mcap/part-0.parquet"
    ]
    text = run_ok(["bag", "echo", str(fleet), "/topic", "--json", "-j", "1"])
    assert {json.loads(line)["bag"] for line in text.splitlines()} == {"talker_mcap"}
    csv = rostool(["bag", "echo", str(fleet / "a.bag"), str(fleet / "b.bag"), "/chatter", "--csv"], env())
    assert csv.returncode == 1 and csv.stderr == (
        "rostool: --csv prints one bag: for several, use `rostool bag export --format csv`\n"
    )


def test_progress_bar_on_a_terminal_keeps_stdout_the_data(fleet: Path) -> None:
    """stderr a terminal (the bar is drawn there), stdout a pipe: every message still goes to stdout."""
    import os
    import subprocess
    import sys

    leader, follower = os.openpty()
    try:
        result = subprocess.run(
            [sys.executable, "-m", "rostool", "bag", "echo", str(fleet), "/chatter", "--json", "-j", "2"],
            env=env(), stdout=subprocess.PIPE, stderr=follower, text=True, timeout=180,
        )  # fmt: skip
    finally:
        os.close(follower)
        os.close(leader)
    assert result.returncode == 0
    assert [json.loads(line)["bag"] for line in result.stdout.splitlines()].count("a") == 30
