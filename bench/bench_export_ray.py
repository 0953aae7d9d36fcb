"""`bag export` spread over cores: the local engine (-j 1, -j 2) against Ray (a private local Ray, and an
already running local head by address), on a fleet of bags and on one big bag cut in pieces.

Bags are generated under --tmp (removed afterwards): rosbag2 .mcap bags mixing sensor_msgs/Imu (decoded
column-wise: ~1 M msg/s on one core) and tf2_msgs/TFMessage (a sequence of messages, decoded one by one:
~20 k msg/s), the CPU-bound mix where more cores pay.
- fleet: --bags bags (copies of one) of --imu Imu and --tf TFMessage each;
- single: one ~1 GB bag of --single-imu Imu alone (fixed layout), and one of --mix-imu Imu and --mix-tf
  TFMessage; each exported whole (-j 1), by the cost rule (-j 2: export_cost.py decides whether to cut),
  and cut in two pieces on purpose (export_many's `piece_bytes`, through a small driver).
The Ray head for --ray-address is started here (`ray start --head --block`, loopback only, token auth, no
dashboard, no usage statistics; its listeners checked with `ss`) and stopped by its own pid at the end.
Every command is a new process; medians of --runs (wall; CPU of the driver and the children it reaped).
Peak RSS: /proc sampled every 50 ms over the command's process tree and the head's workers: the driver's,
and the largest worker's (a local worker process, or a Ray `ray::` worker; Ray's own daemons left out).

Run: .venv/bin/python bench/bench_export_ray.py [--what fleet|single|all] [--runs 3] [--tmp /tmp/h1]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import secrets
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_columnar import messages

IMU, TF = "sensor_msgs/msg/Imu", "tf2_msgs/msg/TFMessage"
RAY = str(Path(sys.executable).parent / "ray")
FORCED = """
import sys
from pathlib import Path
from rostool.bag.export import ExportOptions
from rostool.bag.export_many import export_bags
from rostool.bag.many import expand
bag, out, jobs, piece_bytes, engine = sys.argv[1:6]
runner = None
if engine == "ray":
    from rostool.bag.ray_engine import runner as ray_runner
    runner = ray_runner(None)
Path(out).mkdir()
options = ExportOptions(fmt="parquet", out=Path(out))
export_bags(expand([bag]), options, None, int(jobs), False, runner, int(piece_bytes))
"""


def write_bag(path: Path, imu: int, tf: int) -> Path:
    """One rosbag2 .mcap: `imu` Imu and `tf` TFMessage, interleaved in time."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    imus, tfs = messages(store, IMU, 2000), messages(store, TF, 2000)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        imu_conn = writer.add_connection("/imu", IMU, typestore=store)
        tf_conn = writer.add_connection("/tf", TF, typestore=store)
        every = max(1, imu // tf) if tf else 0
        sent_tf = 0
        for i in range(imu):
            when = 1_000_000_000 + i * 1000
            writer.write(imu_conn, when, imus[i % len(imus)])
            if every and not i % every and sent_tf < tf:
                writer.write(tf_conn, when + 1, tfs[sent_tf % len(tfs)])
                sent_tf += 1
        for k in range(sent_tf, tf):
            writer.write(tf_conn, 1_000_000_000 + imu * 1000 + k, tfs[k % len(tfs)])
    return path


class Sampler:
    """Peak RSS (MiB) of the driver and of its largest worker, from /proc every 50 ms."""

    DAEMONS = ("gcs_server", "raylet", "dashboard", "log_monitor", "monitor.py", "runtime_env", "ray start")

    def __init__(self, driver: int, also: int | None) -> None:
        self.roots = {driver} | ({also} if also else set())
        self.driver = driver
        self.peak: dict[int, int] = {}
        self.kind: dict[int, str] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            parents: dict[int, int] = {}
            for entry in os.scandir("/proc"):
                if entry.name.isdigit():
                    with contextlib.suppress(OSError, ValueError, IndexError):
                        stat = Path(f"/proc/{entry.name}/stat").read_text()
                        parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
            tree = set(self.roots)
            grown = True
            while grown:
                more = {pid for pid, parent in parents.items() if parent in tree} - tree
                tree |= more
                grown = bool(more)
            for pid in tree:
                with contextlib.suppress(OSError, ValueError):
                    status = Path(f"/proc/{pid}/status").read_text()
                    hwm = next(
                        (int(line.split()[1]) for line in status.splitlines() if line.startswith("VmHWM")), 0
                    )
                    self.peak[pid] = max(self.peak.get(pid, 0), hwm)
                    if pid not in self.kind:
                        self.kind[pid] = (
                            Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
                        )
            self._stop.wait(0.05)

    def stop(self) -> tuple[float, float]:
        self._stop.set()
        self._thread.join()
        workers = [
            peak
            for pid, peak in self.peak.items()
            if pid not in self.roots and not any(name in self.kind.get(pid, "") for name in self.DAEMONS)
        ]
        return self.peak.get(self.driver, 0) / 1024, max(workers, default=0) / 1024


def timed(command: list[str], env: dict[str, str], runs: int, out: Path, head: int | None) -> list[float]:
    """Medians of wall s, CPU s, driver MiB, largest worker MiB."""
    rows = []
    for _ in range(runs):
        shutil.rmtree(out, ignore_errors=True)
        start = time.perf_counter()
        proc = subprocess.Popen(
            command, env=env, cwd=out.parent, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        sampler = Sampler(proc.pid, head)
        _pid, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        driver, worker = sampler.stop()
        if status:
            raise SystemExit(f"{command} failed: {proc.stderr.read().decode() if proc.stderr else ''}")
        rows.append([wall, usage.ru_utime + usage.ru_stime, driver, worker])
    return [statistics.median(column) for column in zip(*rows, strict=True)]


@contextlib.contextmanager
def ray_head(env: dict[str, str], tmp: Path) -> Iterator[tuple[dict[str, str], int]]:
    """A Ray head on 127.0.0.1 of this run's own (token auth), and the env and pid to reach it."""
    port = 26379
    home = tmp / "rayhome"
    home.mkdir()
    head_env = {**env, "HOME": str(home), "TMPDIR": str(home), "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
    head_env.update(RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32), RAY_USAGE_STATS_ENABLED="0")
    command = [RAY, "start", "--head", "--block", "--node-ip-address", "127.0.0.1", "--port", str(port)]
    command += ["--num-cpus", str(os.cpu_count()), "--include-dashboard", "false", "--disable-usage-stats"]
    log = (home / "head.log").open("w")
    head = subprocess.Popen(command, env=head_env, stdout=log, stderr=subprocess.STDOUT)
    try:
        listeners: list[str] = []
        for _ in range(300):
            out = subprocess.run(["ss", "-tlnpH"], capture_output=True, text=True, check=False).stdout
            listeners = [
                line.split()[3] for line in out.splitlines() if "raylet" in line or "gcs_server" in line
            ]
            if any(f":{port}" in address for address in listeners) and len(listeners) >= 2:
                break
            time.sleep(0.1)
        loopback = ("127.0.0.1:", "[::ffff:127.0.0.1]:")
        if not listeners or not all(address.startswith(loopback) for address in listeners):
            raise SystemExit(f"the Ray head listens beyond loopback or not at all: {listeners}")
        print(f"Ray head: listeners {', '.join(sorted(listeners))} (all loopback)")
        yield {**head_env, "RAY_ADDRESS": f"127.0.0.1:{port}"}, head.pid
    finally:
        head.send_signal(signal.SIGTERM)
        try:
            head.wait(60)
        except subprocess.TimeoutExpired:
            head.kill()
        log.close()


def table(rows: list[tuple[str, str, list[float]]], messages_count: int) -> None:
    print("| bags | engine | wall s | CPU s | vs -j 1 (wall) | msg/s (wall) | driver MiB | worker MiB |")
    print("|---|---|---|---|---|---|---|---|")
    base = rows[0][2][0]
    for label, engine, (wall, cpu, driver, worker) in rows:
        speed = f"{base / wall:.2f}x | {messages_count / wall:,.0f}"
        print(f"| {label} | {engine} | {wall:.2f} | {cpu:.2f} | {speed} | {driver:.0f} | {worker:.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--what", choices=("fleet", "single", "all"), default="all")
    parser.add_argument("--bags", type=int, default=4)
    parser.add_argument("--imu", type=int, default=150_000, help="Imu messages per bag of the fleet")
    parser.add_argument("--tf", type=int, default=110_000, help="TFMessage messages per bag of the fleet")
    parser.add_argument("--single-imu", type=int, default=2_900_000)
    parser.add_argument("--mix-imu", type=int, default=2_600_000)
    parser.add_argument("--mix-tf", type=int, default=150_000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--tmp", default=os.environ.get("BENCH_TMP"))
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_")}
    env.update(RAY_USAGE_STATS_ENABLED="0", AWS_EC2_METADATA_DISABLED="true")
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} at start")
    with tempfile.TemporaryDirectory(prefix="bench-ray-", dir=args.tmp) as tmp_name:
        tmp = Path(tmp_name)
        with ray_head(env, tmp) as (head_env, head_pid):
            export = [sys.executable, "-m", "rostool", "bag", "export"]
            address = ["--engine", "ray", "--ray-address", head_env["RAY_ADDRESS"]]
            if args.what in ("fleet", "all"):
                fleet = tmp / "fleet"
                fleet.mkdir()
                write_bag(fleet / "bag0", args.imu, args.tf)
                for index in range(1, args.bags):
                    shutil.copytree(fleet / "bag0", fleet / f"bag{index}")
                total = args.bags * (args.imu + args.tf)
                each = f"{args.imu:,} Imu + {args.tf:,} TFMessage"
                print(f"\nfleet: {args.bags} bags of {each} ({total:,} messages)")
                out = tmp / "out"
                rows = []
                for engine, extra, run_env, head in (
                    ("local -j 1", ["-j", "1"], env, None),
                    ("local -j 2", ["-j", "2"], env, None),
                    ("ray, private local", ["--engine", "ray"], env, None),
                    ("ray --ray-address (running head)", address, head_env, head_pid),
                ):
                    command = [*export, str(fleet), "-o", str(out), *extra]
                    rows.append((f"{args.bags}", engine, timed(command, run_env, args.runs, out, head)))
                    print(f"  {engine}: {rows[-1][2][0]:.2f} s (load {os.getloadavg()[0]:.1f})", flush=True)
                table(rows, total)
                shutil.rmtree(fleet)
            if args.what in ("single", "all"):
                for label, imu, tf in (
                    ("Imu", args.single_imu, 0),
                    ("Imu + TFMessage", args.mix_imu, args.mix_tf),
                ):
                    bag = write_bag(tmp / "one", imu, tf)
                    size = sum(f.stat().st_size for f in bag.iterdir()) / 2**20
                    print(f"\none bag: {label}, {imu + tf:,} messages, {size:,.0f} MiB")
                    out = tmp / "out"
                    forced = [sys.executable, "-c", FORCED, str(bag), str(out)]
                    rows = []
                    for engine, command, run_env, head in (
                        ("-j 1 (whole)", [*export, str(bag), "-o", str(out), "-j", "1"], env, None),
                        ("-j 2, cost rule", [*export, str(bag), "-o", str(out), "-j", "2"], env, None),
                        ("-j 2, two pieces", [*forced, "2", "1", "local"], env, None),
                        (
                            "ray (head), cost rule",
                            [*export, str(bag), "-o", str(out), *address],
                            head_env,
                            head_pid,
                        ),
                        ("ray (head), two pieces", [*forced, "2", "1", "ray"], head_env, head_pid),
                    ):
                        rows.append(("1", engine, timed(command, run_env, args.runs, out, head)))
                        print(
                            f"  {engine}: {rows[-1][2][0]:.2f} s (load {os.getloadavg()[0]:.1f})", flush=True
                        )
                    table(rows, imu + tf)
                    shutil.rmtree(bag)
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
