"""`bag export --engine ray`: the same dataset as the local engine, on a private local Ray and on a Ray
cluster given by address (a head started here on 127.0.0.1); a bad bag is one line naming it; Ray binds
loopback only and writes nothing into the user's ~/.ray."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pyarrow.dataset as ds
import pytest

from tests.support import IN_CI, free_port, rostool, wait_until

# the Ray tests (here and in test_bag_s3.py) run one after another, in one worker: each checks that every
# Ray listener on the machine is on loopback, and several Rays at once on 2 cores only slow each other
pytestmark = pytest.mark.xdist_group("ray")

TESTDATA = Path(__file__).resolve().parents[2] / "shared" / "testdata"
RAY = shutil.which("ray", path=str(Path(sys.executable).parent))


@contextmanager
def ray_env_for(tmp_path: Path) -> Iterator[dict[str, str]]:
    """An environment for Ray: no RAY_ settings of ours, a home of its own, a short TMPDIR."""
    if RAY is None:
        if IN_CI:
            pytest.fail("ray is not installed: the test extra brings it")
        pytest.skip("ray is not installed")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("RAY_", "AWS_"))}
    short = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # Ray's Unix sockets live here: 107 bytes at most
    home = tmp_path / "home"
    home.mkdir(exist_ok=True)
    # no AWS access settings (object storage tests give theirs to rostool only), but never the EC2 metadata
    # address: a credential lookup must not leave loopback
    env.update(HOME=str(home), RAY_USAGE_STATS_ENABLED="0", TMPDIR=short, AWS_EC2_METADATA_DISABLED="true")
    try:
        yield env
    finally:
        shutil.rmtree(short, ignore_errors=True)


@pytest.fixture
def ray_env(tmp_path: Path) -> Iterator[dict[str, str]]:
    with ray_env_for(tmp_path) as env:
        yield env


def _fleet(tmp_path: Path) -> Path:
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    for name in ("talker_mcap", "talker_sqlite3", "cdr_test_mcap", "split_mcap"):
        shutil.copytree(TESTDATA / "ros2" / name, fleet / name)
    return fleet


def _tables(out: Path) -> dict[str, object]:
    """Each topic's dataset as one table, rows in a fixed order (bag, then t)."""
    tables = {}
    for topic in sorted(p for p in out.iterdir() if p.is_dir()):
        table = ds.dataset(topic, format="parquet", partitioning="hive").to_table()
        tables[topic.name] = table.sort_by([("bag", "ascending"), ("t", "ascending")])
    return tables


def _ray_listeners() -> list[str]:
    """Addresses Ray's processes listen on (TCP), from ss."""
    out = subprocess.run(["ss", "-tlnpH"], capture_output=True, text=True, check=False).stdout
    return [line.split()[3] for line in out.splitlines() if any(n in line for n in ("raylet", "gcs_server"))]


def test_private_local_ray_exports_what_the_local_engine_does(
    tmp_path: Path, ray_env: dict[str, str]
) -> None:
    fleet = _fleet(tmp_path)
    local = rostool(["bag", "export", str(fleet), "-o", str(tmp_path / "local")], ray_env, timeout=120)
    assert local.returncode == 0, local.stderr
    run = rostool(
        ["bag", "export", str(fleet), "-o", str(tmp_path / "ray"), "--engine", "ray"], ray_env, timeout=180
    )
    assert run.returncode == 0, run.stderr
    # no Ray log line leaks: the one summary line, as the local engine's
    assert run.stderr.replace("/ray", "/local").strip().splitlines() == local.stderr.strip().splitlines()
    got, want = _tables(tmp_path / "ray"), _tables(tmp_path / "local")
    assert got.keys() == want.keys() and got
    for topic, table in want.items():
        assert got[topic].equals(table), topic
    assert not (tmp_path / "home" / ".ray").exists()  # no auth token left in the user's home


@contextmanager
def ray_head(env: dict[str, str]) -> Iterator[dict[str, str]]:
    """A Ray head on 127.0.0.1 (its own token), checked to listen on loopback only; the client's env."""
    port = free_port()
    head_env = {**env, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0", "RAY_AUTH_MODE": "token"}
    head_env["RAY_AUTH_TOKEN"] = "a" * 64
    assert RAY is not None
    start = [RAY, "start", "--head", "--block", "--node-ip-address", "127.0.0.1", "--port", str(port)]
    start += ["--num-cpus", "2", "--include-dashboard", "false", "--disable-usage-stats"]
    # stopped by its own pid (`--block`: its daemons go with it), not by `ray stop`, which ends every Ray
    # on the machine (another session's included)
    head = subprocess.Popen(start, env=head_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        assert wait_until(lambda: head.poll() is not None or _listening(port), 120)
        assert head.poll() is None, head.stderr.read().decode() if head.stderr else ""
        loopback = ("127.0.0.1:", "[::ffff:127.0.0.1]:")
        assert all(a.startswith(loopback) for a in _ray_listeners()), _ray_listeners()
        # the client without RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER: rostool keeps a loopback address on loopback
        client = {k: v for k, v in head_env.items() if k != "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"}
        yield {**client, "RAY_ADDRESS": f"127.0.0.1:{port}"}
    finally:
        head.terminate()
        try:
            head.wait(60)
        except subprocess.TimeoutExpired:
            head.kill()
            head.wait()


def _listening(port: int) -> bool:
    return any(address.endswith(f":{port}") for address in _ray_listeners())


def test_a_ray_cluster_by_address_and_a_bad_bag(tmp_path: Path, ray_env: dict[str, str]) -> None:
    fleet = _fleet(tmp_path)
    (fleet / "broken.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 64)
    with ray_head(ray_env) as client_env:
        out = tmp_path / "out"
        failed = rostool(
            ["bag", "export", str(fleet), "-o", str(out), "--engine", "ray"], client_env, timeout=180
        )
        assert failed.returncode != 0
        assert len(failed.stderr.strip().splitlines()) == 1 and "broken.mcap" in failed.stderr, failed.stderr
        kept = rostool(
            ["bag", "export", str(fleet), "-o", str(out), "--engine", "ray", "--keep-going"],
            client_env,
            timeout=180,
        )
        assert kept.returncode != 0
        assert "skipped" in kept.stderr and "broken.mcap" in kept.stderr
        bags = {bag for table in _tables(out).values() for bag in table.column("bag").to_pylist()}
        assert bags == {
            "talker_mcap",
            "talker_sqlite3",
            "cdr_test_mcap",
            "split_mcap",
        }  # each good bag's rows


def test_a_cluster_address_nothing_answers_at_is_one_line(tmp_path: Path, ray_env: dict[str, str]) -> None:
    address = f"127.0.0.1:{free_port()}"
    args = ["bag", "export", str(_fleet(tmp_path)), "-o", str(tmp_path / "out"), "--engine", "ray"]
    failed = rostool([*args, "--ray-address", address], ray_env, timeout=60)
    assert failed.returncode == 1
    assert failed.stderr.strip().splitlines() == [
        f"rostool: cannot reach the Ray cluster at {address}: Connection refused"
    ], failed.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


API_SCRIPT = """
import collections, json, sys
import pyarrow.parquet as pq
from rostool.data import read_bag_table, read_bags
out, bags = sys.argv[1], sys.argv[2:]
table = read_bag_table(bags[0], "/topic")
ds = read_bags(bags, topics=["/topic"])
rows = ds.filter(lambda row: row["bag"] == "talker_mcap").take_all()
ds.write_parquet(out)
written = pq.read_table(out)
counts = collections.Counter(written.column("bag").to_pylist())
print(json.dumps({"table": table.to_pylist(), "columns": ds.columns(), "counts": counts, "rows": rows}))
"""


def test_python_api_tables_and_ray_dataset(tmp_path: Path, ray_env: dict[str, str]) -> None:
    """read_bag_table gives export's table; read_bags a Ray Dataset of the same rows with bag and topic, which
    Ray Data filters and writes as Parquet."""
    import pyarrow.parquet as pq

    fleet = _fleet(tmp_path)
    bags = [str(fleet / "talker_mcap"), str(fleet / "talker_sqlite3")]
    run = subprocess.run(
        [sys.executable, "-c", API_SCRIPT, str(tmp_path / "written"), *bags],
        env=ray_env,
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    exported = rostool(["bag", "export", bags[0], "-o", str(tmp_path / "out")], ray_env, timeout=60)
    assert exported.returncode == 0, exported.stderr
    want = pq.read_table(tmp_path / "out" / "topic.parquet").to_pylist()
    assert got["table"] == want and len(want) == 10
    assert got["columns"] == ["t", "data", "bag", "topic"]
    assert got["counts"] == {"talker_mcap": 10, "talker_sqlite3": 10}
    assert [{k: r[k] for k in ("t", "data")} for r in got["rows"]] == want
    assert {r["topic"] for r in got["rows"]} == {"/topic"}
