"""Coverage-guided fuzzing (atheris / libFuzzer) of the bag readers' parsing entry points.

    .venv/bin/pip install atheris      # 3.0.0 is the newest wheel this index serves for CPython 3.11
    .venv/bin/python bench/atheris_fuzz.py TARGET [--seconds 120] [--work DIR] [libFuzzer flags...]

TARGET: bag (ROS 1 .bag), mcap (bare .mcap), db3 (bare .db3), metadata (a rosbag2 directory's
metadata.yaml beside an intact .mcap), reindex (`bag reindex` of a .bag or .mcap). Each input is written
to a file under /dev/shm and goes through what the CLI does with it: `bag_info` (bag info), BagReader
with every message read and deserialized (bag echo), or `reindex` (then the result read back). A
RostoolError (the one-line message the CLI prints) is the expected way to refuse a damaged input; any
other exception escaping is a finding: atheris stops, prints the traceback and saves the input as
crash-* in the working directory. The seed corpus is made from small intact bags of every format.
rostool's bag modules, rosbags and mcap are instrumented for coverage.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
TESTDATA = Path(os.environ.get("ROSTOOL_TESTDATA", "/work/shared/testdata"))
TARGETS = ("bag", "mcap", "db3", "metadata", "reindex")


def make_corpus(target: str, corpus: Path) -> None:
    """Small intact inputs: libFuzzer mutates these."""
    from tests.test_bag_support import write_ros1_bag

    corpus.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix="seeds-"))
    try:
        if target in ("bag", "reindex"):
            for compression in (None, "bz2", "lz4"):
                bag = write_ros1_bag(scratch / f"s_{compression}.bag", count=12, compression=compression)
                shutil.copy(bag, corpus / bag.name)
            shutil.copy(TESTDATA / "ros1" / "no-messages.bag", corpus / "no-messages.bag")
        if target in ("mcap", "reindex"):
            shutil.copy(TESTDATA / "ros2" / "talker_mcap" / "talker.mcap", corpus / "talker.mcap")
            shutil.copy(TESTDATA / "ros2" / "cdr_test_mcap" / "cdr_test_0.mcap", corpus / "cdr_test.mcap")
        if target == "db3":
            shutil.copy(TESTDATA / "ros2" / "talker_sqlite3" / "talker.db3", corpus / "talker.db3")
        if target == "metadata":
            for name in ("talker_mcap", "split_mcap", "cdr_test_mcap"):
                shutil.copy(TESTDATA / "ros2" / name / "metadata.yaml", corpus / f"{name}.yaml")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def harness(target: str, work: Path) -> Callable[[bytes], None]:
    from rostool.bag.info import bag_info
    from rostool.bag.reader import BagReader
    from rostool.bag.reindex import reindex
    from rostool.errors import RostoolError

    suffix = {"bag": ".bag", "mcap": ".mcap", "db3": ".db3", "metadata": ".yaml", "reindex": ""}[target]
    rosbag2 = work / "rosbag2"
    if target == "metadata":  # metadata.yaml beside the storage file it names
        rosbag2.mkdir(parents=True, exist_ok=True)
        shutil.copy(TESTDATA / "ros2" / "talker_mcap" / "talker.mcap", rosbag2 / "talker.mcap")

    def read_all(path: Path) -> None:
        bag_info(path)
        with BagReader([path]) as reader:
            for conn, _stamp, raw in reader.messages(reader.connections):
                reader.deserialize(raw, conn)

    def one_input(data: bytes) -> None:
        if target == "metadata":
            path = rosbag2
            (rosbag2 / "metadata.yaml").write_bytes(data)
        elif target == "reindex":
            for leftover in work.glob("victim*"):
                leftover.unlink()
            is_bag = data.startswith(b"#ROSBAG")
            path = work / ("victim.bag" if is_bag else "victim.mcap")
            path.write_bytes(data)
        else:
            path = work / f"input{suffix}"
            path.write_bytes(data)
        try:
            if target == "reindex":
                reindex(path)
                read_all(path)
            else:
                read_all(path)
        except RostoolError:
            pass  # the one-line refusal the CLI prints

    return one_input


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("target", choices=TARGETS)
    parser.add_argument("--seconds", type=int, default=120)
    parser.add_argument("--work", type=Path, default=None, help="corpus and scratch (default: /dev/shm)")
    args, libfuzzer = parser.parse_known_args()

    import atheris

    with atheris.instrument_imports(include=["rostool.bag", "rosbags", "mcap"]):
        import mcap.reader  # noqa: F401
        import rosbags.rosbag1
        import rosbags.rosbag2  # noqa: F401

        import rostool.bag.info
        import rostool.bag.reader
        import rostool.bag.reindex  # noqa: F401

    base = args.work or Path(tempfile.mkdtemp(prefix=f"atheris-{args.target}-", dir="/dev/shm"))
    corpus, scratch = base / "corpus", base / "scratch"
    scratch.mkdir(parents=True, exist_ok=True)
    if not corpus.exists():
        make_corpus(args.target, corpus)
    one_input = harness(args.target, scratch)
    flags = [f"-max_total_time={args.seconds}", "-rss_limit_mb=3072", "-timeout=20", "-max_len=65536"]
    atheris.Setup([sys.argv[0], *flags, *libfuzzer, str(corpus)], one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
