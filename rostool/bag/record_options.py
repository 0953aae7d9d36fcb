"""What `bag record` is asked for and what it reports (`RecordOptions`, `RecordStatus`, `RecordResult`),
and where it writes: rosbag's file names and the checks on them before anything is created."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal, cast

from rostool.bag.formats import FORMATS, by_suffix
from rostool.bag.record_silence import Silence
from rostool.bag.record_sinks import active_name
from rostool.bag.replace import check_replaceable
from rostool.bag.rosbag2_dir import Rosbag2Layout
from rostool.errors import RostoolError

if TYPE_CHECKING:
    from rostool.bag.storage_config import StorageConfig

Format = Literal["bag", "mcap", "db3"]  # the formats of a file: the kinds of formats.FILES


@dataclass
class RecordOptions:
    topics: Sequence[str] = ()
    all_topics: bool = False
    regex: bool = False  # TOPICS are regular expressions (rosbag's -e)
    exclude: str | None = None
    output_name: str | None = None  # -O: exact name (a trailing .bag is optional)
    output_prefix: str | None = None  # -o: NAME_YYYY-MM-DD-HH-MM-SS.bag
    fmt: Format | None = None
    duration: float | None = None  # total, or per file with split
    size: int | None = None  # bytes: stop, or per file with split
    split: bool = False
    max_splits: int | None = None  # with split: keep at most N files, deleting the oldest
    limit: int | None = None  # record at most N messages per topic
    node: str | None = None  # record the topics this node subscribes to (rosbag's --node)
    default_fmt: Format = "bag"  # without -O/-o suffix or --format
    buffer_bytes: int = 256 * 1024 * 1024
    compression: str = "none"
    force: bool = False
    # ROS 2 forms (`ros2 bag record`): a rosbag2 directory (None: one file), which topics, which clock
    rosbag2: Rosbag2Layout | None = None
    wanted: Callable[[str], bool] | None = None  # replaces -a/-e/-x matching when given
    use_sim_time: bool = False  # stamp with the latest /clock; nothing is written before the first one
    start_paused: bool = False  # take no message until resumed (ros2 bag record --start-paused)
    max_rates: Mapping[str, float] = field(default_factory=dict)  # topic -> at most this many messages/s
    # --snapshot-mode: keep the newest messages in memory (at most `buffer_bytes`, and `snapshot_seconds`
    # of them when > 0) and write them only when a snapshot is asked for (SIGUSR2, key 's')
    snapshot: bool = False
    snapshot_seconds: float = 0.0
    storage_config: StorageConfig | None = None  # --storage-config-file, for .mcap and .db3 files
    # --static-topics-path: topic -> type, subscribed at once with that type (no publisher waited for)
    static_topics: Mapping[str, str] = field(default_factory=dict)


@dataclass
class TopicStatus:
    messages: int = 0  # written
    bytes: int = 0  # written (as received)
    dropped: int = 0  # the disk could not keep up
    throttled: int = 0  # left out by --max-rate


@dataclass
class RecordStatus:
    path: Path  # the file being written (its .active name)
    messages: int
    bytes: int
    topics: int
    dropped: int
    paused: bool = False
    buffered: int | None = None  # snapshot mode: messages held in memory
    per_topic: dict[str, TopicStatus] = field(default_factory=dict)


@dataclass
class RecordResult:
    files: list[Path] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)  # topic -> why some messages were not written
    removed: list[Path] = field(default_factory=list)  # older split files deleted by --max-splits
    silences: list[Silence] = field(default_factory=list)  # where a steady topic went quiet for a while
    error: str | None = None

    @property
    def messages(self) -> int:
        return sum(self.counts.values())


def parse_max_rates(values: Sequence[str]) -> dict[str, float]:
    """`--max-rate TOPIC:HZ` values (repeatable)."""
    rates = {}
    for value in values:
        topic, sep, hz = value.rpartition(":")
        try:
            rate = float(hz)
        except ValueError:
            rate = 0.0
        if not sep or not topic or not rate > 0:
            raise RostoolError(f"--max-rate {value!r}: expected TOPIC:HZ with HZ > 0, e.g. /camera/image:2")
        rates[topic] = rate
    return rates


# -- names ---------------------------------------------------------------------------------------
def output_format(options: RecordOptions) -> Format:
    given = options.output_name or options.output_prefix or ""
    named = by_suffix(Path(given).suffix.lower())
    by_name = cast("Format | None", named.kind if named is not None else None)
    if options.fmt is not None:
        if by_name is not None and by_name != options.fmt and options.output_name:
            raise RostoolError(f"{given}: the name says {by_name} but --format says {options.fmt}")
        return options.fmt
    return by_name or options.default_fmt


def target_name(
    options: RecordOptions, fmt: Format, split_index: int | None, now: float | None = None
) -> Path:
    """rosbag's names: PREFIX (without .bag), then _DATE unless -O, then _N when splitting, then .bag."""
    suffix = FORMATS[fmt].suffix
    prefix = options.output_name if options.output_name is not None else options.output_prefix or ""
    for strip in {".bag", suffix}:
        if prefix.endswith(strip):
            prefix = prefix[: -len(strip)]
            break
    parts = [prefix] if prefix else []
    if options.output_name is None:
        parts.append(time.strftime("%Y-%m-%d-%H-%M-%S", time.localtime(now)))
    if split_index is not None:
        parts.append(str(split_index))
    if not parts:
        raise RostoolError("the output name is empty; give -O NAME or -o PREFIX")
    return Path("_".join(parts) + suffix)


def check_target(path: Path, force: bool) -> None:
    parent = path.parent
    if not parent.exists():
        raise RostoolError(f"{path}: cannot record: directory {parent} does not exist")
    if not parent.is_dir():
        raise RostoolError(f"{path}: cannot record: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise RostoolError(f"{path}: cannot record: directory {parent} is not writable")
    for candidate in (path, active_name(path)):
        if (candidate.exists() or candidate.is_symlink()) and not force:
            raise RostoolError(f"{candidate} exists; pass --force to overwrite it")
        check_replaceable(candidate)
