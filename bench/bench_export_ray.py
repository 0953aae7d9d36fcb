"""`bag export` spread over cores: the local engine (-j 1, -j 2) against Ray (a private local Ray, and an
already running local head by address), on a fleet of bags and on one big bag cut in pieces.

Bags are generated under --tmp (removed afterwards): rosbag2 .mcap bags mixing sensor_msgs/Imu (decoded
column-wise: ~1 M msg/s on one core) and tf2_msgs/TFMessage (a sequence of messages, decoded one by one:
~40 k msg/s), the CPU-bound mix where more cores pay.
- fleet: --bags bags (copies of one) of --imu Imu and --tf TFMessage each;
- single: one ~1 GB bag of --single-imu Imu alone (fixed layout), and one of --mix-imu Imu and --mix-tf
  TFMessage; each exported whole (-j 1), by the cost rule (-j 2: export_cost.py decides whether to cut),
  and cut in two pieces on purpose (export_many's `piece_bytes`, through a small driver).
The Ray head for --ray-address is started here (`ray start --head --block`, loopback only, token auth, no
dashboard, no usage statistics; its listeners checked with `ss`), warmed by one job (a running head's first
job costs ~2 s more than the next), and stopped by its own pid at the end.
Every command is a new process; medians of --runs (wall; CPU of the driver and the children it reaped).
"cores free": two busy loops for 4 s, their CPU seconds over 4 (2.00 on an idle machine).
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

WARM = """
from rostool.bag.ray_engine import session
with session(None) as ray:
    ray.get(ray.remote(lambda: 0).remote())
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
    """Peak RSS (MiB) of the driver and of its largest worker (a local worker process, forked by the
    forkserver, or a Ray worker, `ray::...`/default_worker.py), from /proc every 50 ms."""

    WORKERS = ("ray::", "default_worker.py", "multiprocessing.forkserver")

    def __init__(self, driver: int, also: int | None) -> None:
        self.roots = {driver} | ({also} if also else set())
        self.driver = driver
        self.peak: dict[int, int] = {}
        self.workers: set[int] = set()
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
                    lines = status.splitlines()
                    hwm = next((int(line.split()[1]) for line in lines if line.startswith("VmHWM")), 0)
                    self.peak[pid] = max(self.peak.get(pid, 0), hwm)
                    command = Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace")
                    if any(mark in command for mark in self.WORKERS):
                        self.workers.add(pid)
            self._stop.wait(0.05)

    def stop(self) -> tuple[float, float]:
        self._stop.set()
        self._thread.join()
        workers = [self.peak[pid] for pid in self.workers if pid not in self.roots]
        return self.peak.get(self.driver, 0) / 1024, max(workers, default=0) / 1024


def timed(command: list[str], env: dict[str, str], runs: int, out: Path, head: Head | None) -> list[float]:
    """Medians of wall s, CPU s, driver MiB, largest worker MiB. A failed run is retried (twice at most):
    another process on the machine may have stopped every Ray (`ray stop --force`); the head is restarted."""
    rows = []
    failures = 0
    while len(rows) < runs:
        if head is not None:
            head.ensure()
        shutil.rmtree(out, ignore_errors=True)
        start = time.perf_counter()
        proc = subprocess.Popen(
            command, env=env, cwd=out.parent, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        sampler = Sampler(proc.pid, head.pid if head is not None else None)
        _pid, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        driver, worker = sampler.stop()
        if status:
            error = proc.stderr.read().decode().strip() if proc.stderr else ""
            failures += 1
            print(f"  (a run failed, retried: {error[:160]})", flush=True)
            if failures > 2:
                raise SystemExit(f"{command} failed: {error}")
            continue
        rows.append([wall, usage.ru_utime + usage.ru_stime, driver, worker])
    return [statistics.median(column) for column in zip(*rows, strict=True)]


class Head:
    """A Ray head on 127.0.0.1 of this run's own (token auth, `ray start --head --block`, stopped by its pid),
    checked to listen on loopback only; `env` reaches it."""

    PORT = 26379

    def __init__(self, env: dict[str, str], tmp: Path) -> None:
        home = tmp / "rayhome"
        home.mkdir()
        self.env = {**env, "HOME": str(home), "TMPDIR": str(home), "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
        self.env.update(RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32))
        self.env["RAY_ADDRESS"] = f"127.0.0.1:{self.PORT}"
        self.log = (home / "head.log").open("w")
        self.proc: subprocess.Popen[bytes] | None = None
        self.pid = 0

    def ensure(self) -> None:
        if self.proc is not None and self.proc.poll() is None and self._listeners():
            return
        self.stop()
        command = [
            RAY,
            "start",
            "--head",
            "--block",
            "--node-ip-address",
            "127.0.0.1",
            "--port",
            str(self.PORT),
        ]
        command += [
            "--num-cpus",
            str(os.cpu_count()),
            "--include-dashboard",
            "false",
            "--disable-usage-stats",
        ]
        head_env = {k: v for k, v in self.env.items() if k != "RAY_ADDRESS"}
        self.proc = subprocess.Popen(command, env=head_env, stdout=self.log, stderr=subprocess.STDOUT)
        self.pid = self.proc.pid
        listeners: list[str] = []
        for _ in range(300):
            listeners = self._listeners()
            if any(f":{self.PORT}" in address for address in listeners) and len(listeners) >= 2:
                break
            time.sleep(0.1)
        loopback = ("127.0.0.1:", "[::ffff:127.0.0.1]:")
        if not listeners or not all(address.startswith(loopback) for address in listeners):
            raise SystemExit(f"the Ray head listens beyond loopback or not at all: {listeners}")
        print(f"  (Ray head started: listeners {', '.join(sorted(listeners))}, all loopback)", flush=True)
        # a "running" head: its first job pays ~2 s more than the next ones (measured 9.1 s, then 7.0, 6.7)
        start = time.perf_counter()
        warm = [sys.executable, "-c", WARM]
        subprocess.run(warm, env=self.env, check=True, capture_output=True, timeout=300)
        print(f"  (warmed by one job of one task: {time.perf_counter() - start:.1f} s)", flush=True)

    def _listeners(self) -> list[str]:
        out = subprocess.run(["ss", "-tlnpH"], capture_output=True, text=True, check=False).stdout
        return [line.split()[3] for line in out.splitlines() if "raylet" in line or "gcs_server" in line]

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        self.proc = None


def _spin(seconds: float) -> float:
    start, cpu = time.perf_counter(), time.process_time()
    while time.perf_counter() - start < seconds:
        pass
    return time.process_time() - cpu


def cores_free(seconds: float = 4.0) -> float:
    """How many cores the machine gives two busy processes now (2.0 on an idle 2-core machine): what every
    ratio of a parallel run is bounded by when other work shares the machine."""
    import multiprocessing

    with multiprocessing.get_context("fork").Pool(2) as pool:
        return sum(pool.map(_spin, [seconds, seconds])) / seconds


def table(rows: list[tuple[str, str, list[float]]], messages_count: int) -> None:
    print("| bags | engine | wall s | CPU s | vs -j 1 (wall) | msg/s (wall) | driver MiB | worker MiB |")
    print("|---|---|---|---|---|---|---|---|")
    base = rows[0][2][0]
    for label, engine, (wall, cpu, driver, worker) in rows:
        speed = f"{base / wall:.2f}x | {messages_count / wall:,.0f}"
        print(f"| {label} | {engine} | {wall:.2f} | {cpu:.2f} | {speed} | {driver:.0f} | {worker:.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--what", choices=("fleet", "imu", "mix", "all"), default="all")
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
    load = os.getloadavg()[0]
    print(f"{os.cpu_count()} CPUs, load average {load:.1f}, {cores_free():.2f} cores free at start")
    with tempfile.TemporaryDirectory(prefix="bench-ray-", dir=args.tmp) as tmp_name:
        tmp = Path(tmp_name)
        head = Head(env, tmp)
        try:
            run(args, env, head, tmp)
        finally:
            head.stop()
    print(f"\nload average {os.getloadavg()[0]:.1f}, {cores_free():.2f} cores free at the end")


def run(args: argparse.Namespace, env: dict[str, str], head: Head, tmp: Path) -> None:
    export = [sys.executable, "-m", "rostool", "bag", "export"]
    address = ["--engine", "ray", "--ray-address", head.env["RAY_ADDRESS"]]
    out = tmp / "out"
    if args.what in ("fleet", "all"):
        fleet = tmp / "fleet"
        fleet.mkdir()
        write_bag(fleet / "bag0", args.imu, args.tf)
        for index in range(1, args.bags):
            shutil.copytree(fleet / "bag0", fleet / f"bag{index}")
        total = args.bags * (args.imu + args.tf)
        print(f"\nfleet: {args.bags} bags of {args.imu:,} Imu + {args.tf:,} TFMessage ({total:,} messages)")
        rows = []
        for engine, extra, run_env, by in (
            ("local -j 1", ["-j", "1"], env, None),
            ("local -j 2", ["-j", "2"], env, None),
            ("ray, private local", ["--engine", "ray"], env, None),
            ("ray --ray-address (running head)", address, head.env, head),
        ):
            command = [*export, str(fleet), "-o", str(out), *extra]
            rows.append((f"{args.bags}", engine, timed(command, run_env, args.runs, out, by)))
            print(f"  {engine}: {rows[-1][2][0]:.2f} s (load {os.getloadavg()[0]:.1f})", flush=True)
        table(rows, total)
        shutil.rmtree(fleet)
    singles = [("Imu", args.single_imu, 0)] if args.what in ("imu", "all") else []
    singles += [("Imu + TFMessage", args.mix_imu, args.mix_tf)] if args.what in ("mix", "all") else []
    for label, imu, tf in singles:
        bag = write_bag(tmp / "one", imu, tf)
        size = sum(f.stat().st_size for f in bag.iterdir()) / 2**20
        print(f"\none bag: {label}, {imu + tf:,} messages, {size:,.0f} MiB")
        forced = [sys.executable, "-c", FORCED, str(bag), str(out)]
        whole = [*export, str(bag), "-o", str(out)]
        rows = []
        for engine, command, run_env, by in (
            ("-j 1 (whole)", [*whole, "-j", "1"], env, None),
            ("-j 2, cost rule", [*whole, "-j", "2"], env, None),
            ("-j 2, two pieces", [*forced, "2", "1", "local"], env, None),
            ("ray (head), cost rule", [*whole, *address], head.env, head),
            ("ray (head), two pieces", [*forced, "2", "1", "ray"], head.env, head),
        ):
            rows.append(("1", engine, timed(command, run_env, args.runs, out, by)))
            print(f"  {engine}: {rows[-1][2][0]:.2f} s (load {os.getloadavg()[0]:.1f})", flush=True)
        table(rows, imu + tf)
        shutil.rmtree(bag)


if __name__ == "__main__":
    main()
