"""Fuzz every bag input path: mutated copies of the real test bags through `bag info`, `bag info --json`
and `bag echo --json`, each answered by a clean result or one line on stderr with exit 1.

Formats: ROS 1 .bag (plain, bz2, no messages, a small cut of example.bag), bare .mcap and .db3 files,
rosbag2 directories (a storage file inside damaged), their metadata.yaml, and several bags at once (one
damaged, one intact). Mutations: bit flips, truncation, zeroed ranges, duplicated ranges, planted huge
lengths (at record length fields of .bag/.mcap, at random offsets of .db3, as numbers in metadata.yaml).

Each case runs in-process (click's CliRunner) in one of a few forked workers: a worker has an address-space
limit (a planted length cannot eat the machine) and a per-case deadline (a hung case is counted as a
timeout and its worker replaced); workers are recycled every few hundred cases so no state leaks far.

Outcomes: `clean` (exit 0, stderr only `rostool: warning:` lines), `error` (exit 1, exactly one stderr
line), `internal` (an exception escaped: `rostool: internal error`, exit 70, or a traceback), `multiline`
(an error over several lines), `other` (any other exit code or shape), `timeout`.

Run: .venv/bin/python bench/fuzz_bags.py [--cases 10000] [--seed 14] [--workers 2] [--show 20]
The suite's tests/test_bag_fuzz.py runs a few hundred cases of the same harness.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import random
import re
import shutil
import struct
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from pathlib import Path

TESTDATA = Path(os.environ.get("ROSTOOL_TESTDATA", "/work/shared/testdata"))
FORMATS = ("bag", "mcap", "db3", "rosbag2", "metadata", "several")
COMMANDS = (("info",), ("info", "--json"), ("echo", "--json"))
OUTCOMES = ("clean", "error", "internal", "multiline", "other", "timeout")
MEMORY_LIMIT = 3 << 30  # bytes of address space per worker

ROS2_DIRS = (
    "talker_mcap",
    "talker_sqlite3",
    "cdr_test_mcap",
    "cdr_test_sqlite3",
    "split_mcap",
    "convert_b_mcap",
    "service_events_sqlite3",
    "empty_bag_sqlite3",
)


# -- seeds ---------------------------------------------------------------------------------------
@dataclass
class Seeds:
    """Intact inputs, copied (never touched in place) from the shared test data."""

    root: Path
    bags: list[Path] = field(default_factory=list)
    mcaps: list[Path] = field(default_factory=list)
    db3s: list[Path] = field(default_factory=list)
    dirs: list[Path] = field(default_factory=list)

    def of(self, fmt: str) -> list[Path]:
        return {"bag": self.bags, "mcap": self.mcaps, "db3": self.db3s}.get(fmt, self.dirs)


def make_seeds(root: Path) -> Seeds:
    seeds = Seeds(root)
    ros1 = root / "ros1"
    ros1.mkdir(parents=True)
    for name in ("example.bag", "example-bz2.bag", "no-messages.bag"):
        shutil.copy(TESTDATA / "ros1" / name, ros1 / name)
        seeds.bags.append(ros1 / name)
    small = ros1 / "small.bag"  # a few chunks: echo of a damaged copy stays fast
    _run_cli(["bag", "filter", str(ros1 / "example.bag"), str(small), "--end", "+0.5"])
    if small.exists():
        seeds.bags.append(small)
    for name in ROS2_DIRS:
        target = root / "ros2" / name
        shutil.copytree(TESTDATA / "ros2" / name, target)
        seeds.dirs.append(target)
        for file in sorted(target.iterdir()):
            if (file.suffix == ".mcap" and name != "split_mcap") or file.name == "wbag_0.mcap":
                seeds.mcaps.append(file)
            elif file.suffix == ".db3" and name != "empty_bag_sqlite3":
                seeds.db3s.append(file)
    return seeds


def _run_cli(args: Sequence[str]) -> tuple[int, str, str, BaseException | None]:
    from click.testing import CliRunner

    from rostool.cli import root

    result = CliRunner().invoke(root, list(args), catch_exceptions=True)
    exception = result.exception if not isinstance(result.exception, SystemExit) else None
    return result.exit_code, result.stdout, result.stderr, exception


# -- mutations -----------------------------------------------------------------------------------
HUGE_U32 = (0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0x10000000)
HUGE_U64 = (2**64 - 1, 2**63 - 1, 2**63, 2**40, 2**32)


def record_length_offsets(data: bytes, fmt: str) -> list[tuple[int, str]]:
    """Offsets of the length fields of top-level records: (offset, struct format)."""
    found: list[tuple[int, str]] = []
    if fmt == "bag":
        pos = data.find(b"\n") + 1  # after `#ROSBAG V2.0\n`
        while pos > 0 and pos + 4 <= len(data) and len(found) < 10_000:
            (header_len,) = struct.unpack_from("<I", data, pos)
            found.append((pos, "<I"))
            data_at = pos + 4 + header_len
            if data_at + 4 > len(data):
                break
            found.append((data_at, "<I"))
            (data_len,) = struct.unpack_from("<I", data, data_at)
            pos = data_at + 4 + data_len
    elif fmt == "mcap":
        pos = 8
        while pos + 9 <= len(data) and len(found) < 10_000:
            found.append((pos + 1, "<Q"))
            (length,) = struct.unpack_from("<Q", data, pos + 1)
            pos += 9 + length
    return found


def mutate_bytes(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, str]:
    """One mutation of `data`; returns the new bytes and what was done."""
    size = len(data)
    kind = rng.choice(("bitflip", "truncate", "zero", "duplicate", "huge"))
    if size == 0:
        return data, "none (empty)"
    buf = bytearray(data)
    if kind == "bitflip":
        flips = rng.choice((1, 1, 2, 4, 16))
        where = [rng.randrange(size) for _ in range(flips)]
        for pos in where:
            buf[pos] ^= 1 << rng.randrange(8)
        return bytes(buf), f"bitflip x{flips} at {where[0]}"
    if kind == "truncate":
        cut = rng.randrange(size)
        return bytes(buf[:cut]), f"truncate at {cut}/{size}"
    if kind == "zero":
        start = rng.randrange(size)
        length = min(size - start, rng.choice((1, 4, 64, 512, 4096)))
        buf[start : start + length] = bytes(length)
        return bytes(buf), f"zero {length} at {start}"
    if kind == "duplicate":
        start = rng.randrange(size)
        length = min(size - start, rng.choice((1, 8, 64, 512, 4096)))
        at = rng.randrange(size)
        buf[at:at] = buf[start : start + length]
        return bytes(buf), f"duplicate {length} from {start} to {at}"
    fields = record_length_offsets(data, fmt) if fmt in ("bag", "mcap") else []
    if fields and rng.random() < 0.8:
        pos, form = rng.choice(fields)
    else:
        form = rng.choice((">I", "<I", "<Q"))
        pos = rng.randrange(max(1, size - 8))
    value = rng.choice(HUGE_U64 if form == "<Q" else HUGE_U32)
    width = struct.calcsize(form)
    if pos + width <= size:
        struct.pack_into(form, buf, pos, value)
    return bytes(buf), f"huge {value:#x} ({form}) at {pos}"


_NUMBER = re.compile(rb"(?<![\w.])\d+(?![\w.])")


def mutate_yaml(data: bytes, rng: random.Random) -> tuple[bytes, str]:
    """A metadata.yaml mutation: the byte mutations, or a planted huge/negative number, or a lost line."""
    pick = rng.random()
    if pick < 0.15:
        numbers = list(_NUMBER.finditer(data))
        if numbers:
            match = rng.choice(numbers)
            value = rng.choice((b"99999999999999999999999999", b"-1", b"18446744073709551615", b"1e400"))
            return data[: match.start()] + value + data[match.end() :], f"number -> {value.decode()}"
    if pick < 0.25:
        lines = data.split(b"\n")
        index = rng.randrange(len(lines))
        del lines[index]
        return b"\n".join(lines), f"drop line {index + 1}"
    return mutate_bytes(data, "yaml", rng)


# -- cases ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    number: int
    fmt: str
    command: tuple[str, ...]
    seed: int  # the case's own random seed: picks the input and the mutation


@dataclass
class Outcome:
    case: Case
    kind: str
    detail: str  # mutation and the (first) error line
    seconds: float = 0.0


def plan(count: int, seed: int) -> list[Case]:
    """`count` cases spread evenly over formats and commands, reproducible from `seed`."""
    rng = random.Random(seed)
    cases = []
    for number in range(count):
        fmt = FORMATS[number % len(FORMATS)]
        command = COMMANDS[(number // len(FORMATS)) % len(COMMANDS)]
        cases.append(Case(number, fmt, command, rng.getrandbits(64)))
    return cases


def materialize(case: Case, seeds: Seeds, work: Path) -> tuple[list[str], str]:
    """The mutated input of `case` under `work` (emptied first): the paths to pass, and the mutation."""
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    rng = random.Random(case.seed)
    fmt = case.fmt
    if fmt in ("bag", "mcap", "db3"):
        source = rng.choice(seeds.of(fmt))
        data, what = mutate_bytes(source.read_bytes(), fmt, rng)
        target = work / source.name
        target.write_bytes(data)
        return [str(target)], f"{source.name}: {what}"
    if fmt == "several":
        kind = rng.choice(("bag", "mcap", "db3"))
        source = rng.choice(seeds.of(kind))
        data, what = mutate_bytes(source.read_bytes(), kind, rng)
        target = work / f"mutated{source.suffix}"
        target.write_bytes(data)
        intact = [s for s in seeds.of(kind) if s.stat().st_size < 300_000] or seeds.of(kind)
        other = rng.choice(intact)
        paths = [str(target), str(other)]
        if rng.random() < 0.5:
            paths.reverse()
        return paths, f"{source.name}: {what} (with intact {other.name})"
    source_dir = rng.choice(seeds.dirs)
    target_dir = work / source_dir.name
    shutil.copytree(source_dir, target_dir)
    if fmt == "metadata":
        meta = target_dir / "metadata.yaml"
        data, what = mutate_yaml(meta.read_bytes(), rng)
        meta.write_bytes(data)
        given = str(meta) if rng.random() < 0.25 else str(target_dir)
        return [given], f"{source_dir.name}/metadata.yaml: {what}"
    storages = sorted(p for p in target_dir.iterdir() if p.suffix in (".mcap", ".db3"))
    victim = rng.choice(storages)
    data, what = mutate_bytes(victim.read_bytes(), "mcap" if victim.suffix == ".mcap" else "db3", rng)
    victim.write_bytes(data)
    return [str(target_dir)], f"{source_dir.name}/{victim.name}: {what}"


def arguments(case: Case, paths: list[str]) -> list[str]:
    verb, *options = case.command
    if verb == "echo":
        return ["bag", "echo", *options, paths[0]]  # echo reads one bag
    return ["bag", verb, *options, *paths]


def classify(code: int, stdout: str, stderr: str, exception: BaseException | None) -> tuple[str, str]:
    """(outcome, first line of stderr or the escaped exception)."""
    if exception is not None:
        return (
            "internal",
            f"{type(exception).__name__}: {str(exception).splitlines()[0] if str(exception) else ''}",
        )
    lines = [line for line in stderr.splitlines() if line.strip()]
    first = lines[0] if lines else ""
    if "Traceback" in stderr or "internal error" in stderr or code == 70:
        return "internal", first
    errors = [line for line in lines if not line.startswith("rostool: warning:")]
    if code == 0:
        return ("clean", first) if not errors else ("other", f"exit 0 with stderr: {errors[0]}")
    if code == 1:
        if len(lines) == 1:
            return "error", first
        return "multiline", " | ".join(lines[:4])
    return "other", f"exit {code}: {first}"


def run_case(case: Case, seeds: Seeds, work: Path) -> Outcome:
    started = time.perf_counter()
    paths, what = materialize(case, seeds, work)
    code, stdout, stderr, exception = _run_cli(arguments(case, paths))
    kind, line = classify(code, stdout, stderr, exception)
    return Outcome(case, kind, f"{what} -> {line}", time.perf_counter() - started)


# -- worker pool ---------------------------------------------------------------------------------
def _worker(conn: Connection, seeds: Seeds, work: Path) -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    sys.setrecursionlimit(10_000)
    while True:
        case = conn.recv()
        if case is None:
            return
        try:
            outcome = run_case(case, seeds, work)
        except BaseException as err:  # the harness itself failed: report, never hang the parent
            outcome = Outcome(case, "internal", f"harness: {type(err).__name__}: {err}")
        conn.send(outcome)


@dataclass
class _Slot:
    process: multiprocessing.process.BaseProcess
    conn: Connection
    case: Case | None = None
    deadline: float = 0.0
    done: int = 0


def run_cases(
    cases: Sequence[Case],
    seeds: Seeds,
    workers: int = 2,
    timeout: float = 20.0,
    recycle: int = 300,
    progress: Callable[[int], None] | None = None,
) -> Iterator[Outcome]:
    """Outcomes of `cases`, run on `workers` forked processes (in completion order)."""
    context = multiprocessing.get_context("fork")
    scratch = Path(tempfile.mkdtemp(prefix="rostool-fuzz-work-"))
    serial = 0

    def start() -> _Slot:
        nonlocal serial
        serial += 1
        parent, child = context.Pipe()
        process = context.Process(target=_worker, args=(child, seeds, scratch / str(serial)), daemon=True)
        process.start()
        child.close()
        return _Slot(process, parent)

    def stop(slot: _Slot, kill: bool = False) -> None:
        if kill:
            slot.process.kill()
        else:
            try:
                slot.conn.send(None)
            except OSError:
                slot.process.kill()
        slot.process.join(5)
        slot.conn.close()

    pending = list(reversed(cases))
    slots = [start() for _ in range(max(1, workers))]
    finished = 0
    try:
        while pending or any(slot.case is not None for slot in slots):
            for slot in slots:
                if slot.case is None and pending:
                    slot.case = pending.pop()
                    slot.deadline = time.monotonic() + timeout
                    slot.conn.send(slot.case)
            busy = {slot.conn: slot for slot in slots if slot.case is not None}
            ready = wait(list(busy), timeout=0.5)
            now = time.monotonic()
            for index, slot in enumerate(slots):
                if slot.case is None:
                    continue
                outcome: Outcome | None = None
                replace = False
                if slot.conn in ready:
                    try:
                        outcome = slot.conn.recv()
                    except (EOFError, OSError):  # the worker died (e.g. a crash in C code)
                        outcome = Outcome(slot.case, "internal", "worker process died")
                        replace = True
                elif now > slot.deadline:
                    outcome = Outcome(slot.case, "timeout", f"no answer within {timeout:.0f} s", timeout)
                    replace = True
                if outcome is None:
                    continue
                slot.case = None
                slot.done += 1
                finished += 1
                if replace or slot.done >= recycle:
                    stop(slot, kill=replace)
                    slots[index] = start()
                if progress:
                    progress(finished)
                yield outcome
    finally:
        for slot in slots:
            stop(slot, kill=slot.case is not None)
        shutil.rmtree(scratch, ignore_errors=True)


# -- main ----------------------------------------------------------------------------------------
def tally(outcomes: Sequence[Outcome]) -> dict[str, Counter[str]]:
    table: dict[str, Counter[str]] = {fmt: Counter() for fmt in FORMATS}
    for outcome in outcomes:
        table[outcome.case.fmt][outcome.kind] += 1
    return table


def format_tally(outcomes: Sequence[Outcome]) -> str:
    table = tally(outcomes)
    head = f"{'format':<10} {'cases':>6} " + " ".join(f"{kind:>9}" for kind in OUTCOMES)
    rows = [head]
    total: Counter[str] = Counter()
    for fmt, counts in table.items():
        total.update(counts)
        cells = " ".join(f"{counts[kind]:>9}" for kind in OUTCOMES)
        rows.append(f"{fmt:<10} {sum(counts.values()):>6} {cells}")
    cells = " ".join(f"{total[kind]:>9}" for kind in OUTCOMES)
    rows.append(f"{'total':<10} {sum(total.values()):>6} {cells}")
    return "\n".join(rows)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=14)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds per case")
    parser.add_argument("--show", type=int, default=20, help="print up to N failing cases")
    args = parser.parse_args()

    root = Path(tempfile.mkdtemp(prefix="rostool-fuzz-"))
    started = time.perf_counter()
    try:
        seeds = make_seeds(root / "seeds")
        cases = plan(args.cases, args.seed)
        outcomes: list[Outcome] = []

        def progress(done: int) -> None:
            if done % 500 == 0:
                print(f"  {done}/{len(cases)} cases, {time.perf_counter() - started:.0f} s", file=sys.stderr)

        outcomes = list(run_cases(cases, seeds, args.workers, args.timeout, progress=progress))
    finally:
        shutil.rmtree(root, ignore_errors=True)
    elapsed = time.perf_counter() - started
    bad = sorted((o for o in outcomes if o.kind not in ("clean", "error")), key=lambda o: o.case.number)
    print(f"{len(outcomes)} cases (seed {args.seed}, {args.workers} workers) in {elapsed:.0f} s")
    print(format_tally(outcomes))
    slowest = max(outcomes, key=lambda o: o.seconds, default=None)
    if slowest is not None:
        print(f"slowest case: {slowest.seconds:.2f} s (#{slowest.case.number}, {slowest.case.fmt})")
    for outcome in bad[: args.show]:
        case = outcome.case
        print(f"  #{case.number} {case.fmt} bag {' '.join(case.command)}: {outcome.kind}: {outcome.detail}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
