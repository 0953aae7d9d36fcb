"""Hostile and damaged input for issue 27: bags (.bag, .mcap, .db3) and metadata.yaml through `bag info`,
`bag echo --json` and `bag reindex`, plus bags cut at random points repaired by `bag reindex`, counting
lost messages, peak memory and the time to recover.

Built on fuzz_bags.py (its seeds, byte mutations, forked workers with a 3 GiB address-space limit and a
per-case deadline) with the mutations of issue 27 added:
- `declared`: a chunk's declared uncompressed size planted small or large (.bag `size=` header field,
  .mcap chunk `uncompressed_size`): the bounded inflater must stop there (decompression-bomb shape);
- `alias`: YAML anchors/aliases (a "billion laughs" nest) planted in metadata.yaml;
- `cut`: a bag of 2,000 unique messages in uncompressed chunks (ROS 1 .bag from rostool's recorder writer,
  .mcap from the mcap library) cut at a random byte, then `bag reindex`: every message whose record is
  wholly before the cut must come back, byte for byte ("lost" counts those that do not, "false" any
  message that differs).

Outcomes as in fuzz_bags.py: clean, error (exit 1, one line), internal (exit 70 / traceback / escaped
exception), multiline, other, timeout.

Run: .venv/bin/python bench/fuzz_robust.py [--cases 10000] [--seed 27] [--workers 2]
"""

from __future__ import annotations

import argparse
import random
import re
import resource
import shutil
import struct
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import fuzz_bags
from fuzz_bags import Case, Outcome, Seeds, classify, mutate_bytes, mutate_yaml

FORMATS = ("bag", "mcap", "db3", "metadata", "cut-bag", "cut-mcap")
COMMANDS = (("info",), ("echo", "--json"), ("reindex",))
CUT_COUNT = 2000


@dataclass
class RobustOutcome(Outcome):
    expected: int = 0  # cut cases: messages wholly on disk before the cut
    recovered: int = 0
    false: int = 0
    rss_kb: int = 0  # the worker's peak RSS so far
    extra: dict[str, int] = field(default_factory=dict)


# -- seeds with known messages -------------------------------------------------------------------
def _payload(i: int) -> bytes:
    text = f"{i}:".encode() + random.Random(i).randbytes(120)
    return len(text).to_bytes(4, "little") + text


@dataclass
class Counted:
    path: Path
    ends: list[int]  # file offset where each message's bytes end


def make_counted(root: Path) -> dict[str, Counted]:
    from mcap.writer import CompressionType, Writer

    from rostool.bag.ros1_writer import BagWriter

    root.mkdir(parents=True, exist_ok=True)
    bag = root / "counted.bag"
    writer = BagWriter(bag, chunk_threshold=128 * 1024)
    conn = writer.connection(
        {
            "topic": "/c",
            "type": "std_msgs/String",
            "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1",
            "message_definition": "string data\n",
            "callerid": "/fuzz",
        }
    )
    for i in range(CUT_COUNT):
        writer.write(conn, 1_700_000_000_000_000_000 + i * 1000, _payload(i))
    writer.close()
    mcap = root / "counted.mcap"
    with mcap.open("wb") as out:
        mw = Writer(out, chunk_size=128 * 1024, compression=CompressionType.NONE)
        mw.start("ros2", "fuzz")
        schema = mw.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channel = mw.register_channel("/c", "cdr", schema)
        for i in range(CUT_COUNT):
            mw.add_message(channel, 1_000 + i, b"\x00\x01\x00\x00" + _payload(i), 1_000 + i, i)
        mw.finish()
    found = {}
    for kind, path in (("cut-bag", bag), ("cut-mcap", mcap)):
        data = path.read_bytes()
        ends = []
        at = 0
        for i in range(CUT_COUNT):
            at = data.index(_payload(i), at) + len(_payload(i))
            ends.append(at)
        found[kind] = Counted(path, ends)
    return found


def _recovered(path: Path) -> tuple[int, int]:
    """(messages, messages that are not one of the originals) in a repaired bag."""
    originals = {_payload(i) for i in range(CUT_COUNT)}
    values: list[bytes] = []
    if path.suffix == ".mcap":
        from mcap.reader import make_reader

        with path.open("rb") as stream:
            values = [m.data[4:] for _s, _c, m in make_reader(stream).iter_messages()]
    else:
        from rosbags.rosbag1 import Reader

        with Reader(path) as reader:
            values = [raw for _c, _t, raw in reader.messages()]
    return len(values), sum(value not in originals for value in values)


# -- hostile mutations ---------------------------------------------------------------------------
def plant_declared(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, str]:
    """A chunk whose declared uncompressed size is wrong (small or huge)."""
    buf = bytearray(data)
    value = rng.choice((0, 1, 16, 1000, 0x7FFFFFFF))
    if fmt == "bag":
        spots = [m.end() for m in re.finditer(rb"size=", data)]
        if spots:
            at = rng.choice(spots)
            struct.pack_into("<I", buf, at, value & 0xFFFFFFFF)
            return bytes(buf), f"declared size {value} at {at}"
    elif fmt == "mcap":
        spots = []
        pos = 8
        while pos + 9 <= len(data):
            op, length = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
            if op == 0x06:
                spots.append(pos + 9 + 16)
            pos += 9 + length
        if spots:
            at = rng.choice(spots)
            struct.pack_into("<Q", buf, at, value)
            return bytes(buf), f"chunk uncompressed_size {value} at {at}"
    return mutate_bytes(data, fmt, rng)


def plant_alias(data: bytes, rng: random.Random) -> tuple[bytes, str]:
    """A billion-laughs nest of anchors, one of the metadata's values made an alias into it."""
    depth = rng.choice((3, 6, 9))
    nest = ["x0: &x0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for n in range(1, depth + 1):
        nest.append(f"x{n}: &x{n} [" + ", ".join([f"*x{n - 1}"] * 10) + "]")
    text = data.decode("utf-8", "replace")
    keys = list(re.finditer(r"^(  \w+): .+$", text, re.M))
    if not keys:
        return data, "no key to alias"
    key = rng.choice(keys)
    text = text[: key.start()] + f"{key.group(1)}: *x{depth}" + text[key.end() :]
    return ("\n".join(nest) + "\n" + text).encode(), f"alias nest depth {depth} at {key.group(1).strip()}"


# -- cases ---------------------------------------------------------------------------------------
def plan(count: int, seed: int) -> list[Case]:
    rng = random.Random(seed)
    cases = []
    for number in range(count):
        fmt = FORMATS[number % len(FORMATS)]
        if fmt.startswith("cut"):
            command: tuple[str, ...] = ("reindex",)
        elif fmt in ("metadata", "db3"):
            command = COMMANDS[(number // len(FORMATS)) % 2]  # reindex of a .db3 file is not a thing
        else:
            command = COMMANDS[(number // len(FORMATS)) % len(COMMANDS)]
        cases.append(Case(number, fmt, command, rng.getrandbits(64)))
    return cases


_COUNTED: dict[str, Counted] = {}


def materialize(case: Case, seeds: Seeds, work: Path) -> tuple[list[str], str, int]:
    """The input of `case` under `work`; the paths, what was done, and the messages expected back."""
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    rng = random.Random(case.seed)
    if case.fmt.startswith("cut"):
        counted = _COUNTED[case.fmt]
        data = counted.path.read_bytes()
        cut = rng.randrange(len(data))
        target = work / counted.path.name
        target.write_bytes(data[:cut])
        return (
            [str(target)],
            f"{counted.path.name} cut at {cut}/{len(data)}",
            sum(e <= cut for e in counted.ends),
        )
    if case.fmt == "metadata":
        source_dir = rng.choice(seeds.dirs)
        target_dir = work / source_dir.name
        shutil.copytree(source_dir, target_dir)
        meta = target_dir / "metadata.yaml"
        if rng.random() < 0.3:
            data, what = plant_alias(meta.read_bytes(), rng)
        else:
            data, what = mutate_yaml(meta.read_bytes(), rng)
        meta.write_bytes(data)
        return [str(target_dir)], f"{source_dir.name}/metadata.yaml: {what}", 0
    source = rng.choice(seeds.of(case.fmt))
    if case.fmt in ("bag", "mcap") and rng.random() < 0.3:
        data, what = plant_declared(source.read_bytes(), case.fmt, rng)
    else:
        data, what = mutate_bytes(source.read_bytes(), case.fmt, rng)
    target = work / source.name
    target.write_bytes(data)
    return [str(target)], f"{source.name}: {what}", 0


def run_case(case: Case, seeds: Seeds, work: Path) -> RobustOutcome:
    started = time.perf_counter()
    paths, what, expected = materialize(case, seeds, work)
    verb, *options = case.command
    args = ["bag", verb, *options, paths[0]]
    code, stdout, stderr, exception = fuzz_bags._run_cli(args)
    seconds = time.perf_counter() - started
    kind, line = classify(code, stdout, stderr, exception)
    outcome = RobustOutcome(case, kind, f"{what} -> {line}", seconds, expected=expected)
    if case.fmt.startswith("cut") and code == 0:
        try:
            outcome.recovered, outcome.false = _recovered(Path(paths[0]))
        except Exception as err:  # the repaired file does not read: everything counts as lost
            outcome.detail += f" (repaired file unreadable: {type(err).__name__}: {err})"
    outcome.rss_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return outcome


# -- main ----------------------------------------------------------------------------------------
def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=27)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds per case")
    parser.add_argument("--show", type=int, default=20)
    args = parser.parse_args()

    root = Path(tempfile.mkdtemp(prefix="rostool-fuzz27-"))
    started = time.perf_counter()
    fuzz_bags.run_case = run_case  # the workers (forked) run these cases
    fuzz_bags.FORMATS = FORMATS
    try:
        seeds = fuzz_bags.make_seeds(root / "seeds")
        _COUNTED.update(make_counted(root / "counted"))
        cases = plan(args.cases, args.seed)

        def progress(done: int) -> None:
            if done % 1000 == 0:
                print(f"  {done}/{len(cases)} cases, {time.perf_counter() - started:.0f} s", file=sys.stderr)

        outcomes = list(fuzz_bags.run_cases(cases, seeds, args.workers, args.timeout, progress=progress))
    finally:
        shutil.rmtree(root, ignore_errors=True)
    elapsed = time.perf_counter() - started
    print(f"{len(outcomes)} cases (seed {args.seed}, {args.workers} workers) in {elapsed:.0f} s")
    print("| input | cases | clean | one-line error | internal | multi-line | other | timeout | "
          "lost messages | false messages | peak RSS (MB) | slowest (s) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    bad = []
    for fmt in FORMATS:
        mine = [o for o in outcomes if o.case.fmt == fmt]
        kinds = Counter(o.kind for o in mine)
        lost = sum(max(0, o.expected - o.recovered) for o in mine if isinstance(o, RobustOutcome))
        false = sum(o.false for o in mine if isinstance(o, RobustOutcome))
        rss = max((o.rss_kb for o in mine if isinstance(o, RobustOutcome)), default=0) // 1024
        slowest = max((o.seconds for o in mine), default=0.0)
        cells = " | ".join(str(kinds[k]) for k in fuzz_bags.OUTCOMES)
        lost_cell = str(lost) if fmt.startswith("cut") else "-"
        false_cell = str(false) if fmt.startswith("cut") else "-"
        print(f"| {fmt} | {len(mine)} | {cells} | {lost_cell} | {false_cell} | {rss} | {slowest:.2f} |")
        bad += [o for o in mine if o.kind not in ("clean", "error")]
        bad += [o for o in mine if isinstance(o, RobustOutcome) and (o.recovered < o.expected or o.false)]
    cuts = [o for o in outcomes if o.case.fmt.startswith("cut") and o.kind == "clean"]
    if cuts:
        mean = sum(o.seconds for o in cuts) / len(cuts)
        print(f"time to recover (bag reindex of a cut 2,000-message bag): mean {mean:.3f} s, "
              f"max {max(o.seconds for o in cuts):.3f} s")  # fmt: skip
    for outcome in sorted(bad, key=lambda o: o.case.number)[: args.show]:
        extra = (
            f" expected {outcome.expected} recovered {outcome.recovered}"
            if isinstance(outcome, RobustOutcome)
            else ""
        )
        case = outcome.case
        print(
            f"  #{case.number} {case.fmt} {' '.join(case.command)}: {outcome.kind}: {outcome.detail}{extra}"
        )
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
