"""Bags and tables in object storage (S3 through pyarrow.fs), against a real S3 endpoint: moto's server on
127.0.0.1. export s3 -> s3 and s3 -> local equal the local export; info and echo read a bag from S3; a missing
key is one line."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow.dataset as ds
import pyarrow.fs as pafs
import pytest

from tests.support import IN_CI, free_port, rostool, wait_until

TESTDATA = Path(__file__).resolve().parents[2] / "shared" / "testdata"
MOTO = shutil.which("moto_server", path=str(Path(sys.executable).parent))


@pytest.fixture(scope="module")
def s3() -> Iterator[dict[str, Any]]:
    """A moto S3 server on 127.0.0.1 with a bucket `bags` holding some test bags, and the env to reach it."""
    if MOTO is None:
        if IN_CI:
            pytest.fail("moto_server is not installed: the test extra brings it")
        pytest.skip("moto_server is not installed")
    port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("AWS_")}
    env.update(
        AWS_ACCESS_KEY_ID="testing", AWS_SECRET_ACCESS_KEY="testing", AWS_DEFAULT_REGION="us-east-1",
        AWS_EC2_METADATA_DISABLED="true", AWS_ENDPOINT_URL=f"http://127.0.0.1:{port}",
    )  # fmt: skip
    server = subprocess.Popen(
        [MOTO, "-H", "127.0.0.1", "-p", str(port)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        fs = pafs.S3FileSystem(
            endpoint_override=f"127.0.0.1:{port}", scheme="http", allow_bucket_creation=True,
            access_key="testing", secret_key="testing", region="us-east-1",
        )  # fmt: skip

        def up() -> bool:
            try:
                fs.create_dir("bags")
                return True
            except OSError:
                return False

        assert wait_until(up, 20), "moto did not come up"
        fs.create_dir("tables")
        for name in ("talker_mcap", "talker_sqlite3", "cdr_test_mcap"):
            pafs.copy_files(str(TESTDATA / "ros2" / name), f"bags/fleet/{name}", pafs.LocalFileSystem(), fs)
        pafs.copy_files(
            str(TESTDATA / "ros1" / "example.bag"), "bags/one/example.bag", pafs.LocalFileSystem(), fs
        )
        yield {"env": env, "fs": fs}
    finally:
        server.terminate()
        server.wait(10)


def _tables(fs: Any, root: str) -> dict[str, Any]:
    found = {}
    for info in fs.get_file_info(pafs.FileSelector(root, recursive=False)):
        if info.type == pafs.FileType.Directory:
            table = ds.dataset(info.path, filesystem=fs, format="parquet", partitioning="hive").to_table()
            found[info.base_name] = table.sort_by([("bag", "ascending"), ("t", "ascending")])
    return found


def test_export_from_s3_to_s3_equals_the_local_export(s3: dict[str, Any], tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    for name in ("talker_mcap", "talker_sqlite3", "cdr_test_mcap"):
        shutil.copytree(TESTDATA / "ros2" / name, fleet / name)
    local = rostool(["bag", "export", str(fleet), "-o", str(tmp_path / "local")], s3["env"], timeout=120)
    assert local.returncode == 0, local.stderr
    remote = rostool(["bag", "export", "s3://bags/fleet", "-o", "s3://tables/ds"], s3["env"], timeout=120)
    assert remote.returncode == 0, remote.stderr
    assert remote.stderr.replace("s3://tables/ds", str(tmp_path / "local")) == local.stderr
    want = _tables(pafs.LocalFileSystem(), str(tmp_path / "local"))
    got = _tables(s3["fs"], "tables/ds")
    assert got.keys() == want.keys() and got
    for topic, table in want.items():
        assert got[topic].equals(table), topic


def test_one_bag_from_s3_export_info_echo(s3: dict[str, Any], tmp_path: Path) -> None:
    uri = "s3://bags/one/example.bag"
    out = tmp_path / "out"
    exported = rostool(["bag", "export", uri, "-o", str(out), "--topics", "/rosout"], s3["env"], timeout=120)
    assert exported.returncode == 0, exported.stderr
    local = rostool(
        [
            "bag",
            "export",
            str(TESTDATA / "ros1" / "example.bag"),
            "-o",
            str(tmp_path / "l"),
            "--topics",
            "/rosout",
        ],
        s3["env"],
        timeout=120,
    )
    assert local.returncode == 0, local.stderr
    assert (
        ds.dataset(out / "rosout.parquet")
        .to_table()
        .equals(ds.dataset(tmp_path / "l" / "rosout.parquet").to_table())
    )
    info = rostool(["bag", "info", uri], s3["env"], timeout=60)
    assert info.returncode == 0, info.stderr
    direct_info = rostool(["bag", "info", str(TESTDATA / "ros1" / "example.bag")], s3["env"], timeout=60)
    # rosbag info's layout, the same facts; the path line names where the copy was read
    assert info.stdout.splitlines()[1:] == direct_info.stdout.splitlines()[1:]
    assert "8647" in info.stdout
    echo = rostool(["bag", "echo", uri, "/rosout", "--json"], s3["env"], timeout=60)
    direct = rostool(
        ["bag", "echo", str(TESTDATA / "ros1" / "example.bag"), "/rosout", "--json"], s3["env"], timeout=60
    )
    assert echo.returncode == 0, echo.stderr
    assert echo.stdout == direct.stdout and echo.stdout.strip()


def test_a_missing_key_is_one_line(s3: dict[str, Any], tmp_path: Path) -> None:
    run = rostool(["bag", "export", "s3://bags/nope.mcap", "-o", str(tmp_path / "o")], s3["env"], timeout=60)
    assert run.returncode == 1
    assert run.stderr.strip() == "rostool: s3://bags/nope.mcap: no such file or prefix", run.stderr


@pytest.mark.xdist_group("ray")  # with the other Ray tests: `ray stop --force` ends every Ray on the machine
def test_ray_tasks_read_and_write_s3_with_the_settings_of_the_command(
    s3: dict[str, Any], tmp_path: Path
) -> None:
    """A Ray head started without any AWS setting: the filesystem travels with the tasks."""
    from tests.test_bag_ray import ray_env_for, ray_head

    with ray_env_for(tmp_path) as plain, ray_head(plain) as head:
        client = {**head, **{k: v for k, v in s3["env"].items() if k.startswith("AWS_")}}
        run = rostool(
            ["bag", "export", "s3://bags/fleet", "-o", "s3://tables/viaray", "--engine", "ray"],
            client,
            timeout=240,
        )
        assert run.returncode == 0, run.stderr
    local = rostool(["bag", "export", "s3://bags/fleet", "-o", str(tmp_path / "l")], s3["env"], timeout=120)
    assert local.returncode == 0, local.stderr
    want = _tables(pafs.LocalFileSystem(), str(tmp_path / "l"))
    got = _tables(s3["fs"], "tables/viaray")
    assert got.keys() == want.keys() and got
    for topic, table in want.items():
        assert got[topic].equals(table), topic
