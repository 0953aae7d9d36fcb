"""Input detection: what a path given on the command line is (by content, not by name).

rosbags picks a reader from the file suffix and fails with messages about suffixes; users pass files with
any name, rosbag2 directories without metadata.yaml, or metadata.yaml itself, so this looks at the magic
bytes and the directory contents and says clearly what is wrong when it is not a bag.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, Literal

from rostool.errors import RostoolError, one_line, yaml_problem

BagKind = Literal["bag", "rosbag2", "mcap", "db3"]

ROS1_MAGIC = b"#ROSBAG V"
MCAP_MAGIC = b"\x89MCAP0\r\n"
SQLITE_MAGIC = b"SQLite format 3\x00"
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
STORAGE_SUFFIXES = {".mcap": "mcap", ".db3": "db3"}


@dataclass(frozen=True)
class BagInput:
    """One bag as given by the user: a ROS 1 file, a rosbag2 directory, or bare storage file(s)."""

    path: Path
    kind: BagKind
    files: tuple[Path, ...]  # storage files (the .bag itself for ROS 1)
    storage: str  # `bag` for ROS 1, else the rosbag2 storage identifier: `mcap` or `sqlite3`
    metadata: Path | None = None  # metadata.yaml of a rosbag2 directory

    @property
    def ros_version(self) -> int:
        return 1 if self.kind == "bag" else 2

    @property
    def size(self) -> int:
        extra = [self.metadata] if self.metadata else []
        return sum(path.stat().st_size for path in (*self.files, *extra) if path.exists())


def warn(text: str) -> None:
    """One `rostool: warning:` line on stderr: the command goes on."""
    import click

    click.echo(f"rostool: warning: {one_line(text, 500)}", err=True)


class MetadataError(RostoolError):
    """metadata.yaml cannot be used: `problem` says why (the message also names the file)."""

    def __init__(self, metadata: Path, problem: str) -> None:
        super().__init__(f"{metadata}: {problem}")
        self.problem = problem


def load_metadata(metadata: Path) -> dict[str, Any]:
    """The `rosbag2_bagfile_information` mapping of a metadata.yaml; one-line MetadataError otherwise."""
    import yaml

    try:
        raw = metadata.read_bytes()
    except OSError as err:
        raise MetadataError(metadata, f"cannot read it: {err.strerror or err}") from err
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise MetadataError(
            metadata, f"damaged, not UTF-8 text (byte {raw[err.start]:#04x} at offset {err.start})"
        ) from err
    try:
        info = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError as err:
        raise MetadataError(metadata, f"damaged YAML: {yaml_problem(err)}") from err
    except (RecursionError, MemoryError, ValueError, OverflowError) as err:
        raise MetadataError(metadata, f"damaged YAML: {one_line(str(err)) or type(err).__name__}") from err
    if _shares_containers(info):
        raise MetadataError(
            metadata, "YAML anchors/aliases repeating a list or mapping are refused (rosbag2 writes none)"
        )
    body = info.get("rosbag2_bagfile_information") if isinstance(info, dict) else None
    if not isinstance(body, dict):
        raise MetadataError(metadata, "not rosbag2 metadata (no rosbag2_bagfile_information mapping)")
    return body


def _shares_containers(root: object) -> bool:
    """Whether a list or mapping is reached twice: YAML aliases, which a "billion laughs" nests so that
    walking (printing, converting) the small loaded graph never ends."""
    seen: set[int] = set()
    stack = [root]
    while stack:
        node = stack.pop()
        if isinstance(node, dict | list):
            if id(node) in seen:
                return True
            seen.add(id(node))
            stack.extend(node.values() if isinstance(node, dict) else node)
    return False


def _int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def check_metadata(body: dict[str, Any], metadata: Path) -> tuple[str, list[Path]]:
    """What the readers need from metadata.yaml, checked: (storage identifier, storage files).
    Raises one MetadataError line naming the first problem."""
    try:
        return _check_metadata(body, metadata.parent)
    except RostoolError as err:
        raise MetadataError(metadata, str(err)) from err


def _check_metadata(body: dict[str, Any], directory: Path) -> tuple[str, list[Path]]:
    storage = body.get("storage_identifier")
    if storage not in ("mcap", "sqlite3"):
        raise RostoolError(f"unknown rosbag2 storage {storage!r} (supported: mcap, sqlite3)")
    version = body.get("version")
    if not _int(version) or not 1 <= version <= 9:
        raise RostoolError(f"unsupported rosbag2 metadata version {version!r} (supported: 1 to 9)")
    names = body.get("relative_file_paths")
    if not isinstance(names, list) or not all(isinstance(name, str) and name for name in names):
        raise RostoolError("metadata relative_file_paths is not a list of file names")
    if not names:
        raise RostoolError("it lists no storage files")
    files = [directory / Path(name).name for name in names]
    missing = [file.name for file in files if not file.is_file()]
    if missing:
        raise RostoolError(f"storage files it lists are missing: {', '.join(missing)}")
    for key, inner in (("starting_time", "nanoseconds_since_epoch"), ("duration", "nanoseconds")):
        entry = body.get(key)
        if not isinstance(entry, dict) or not _int(entry.get(inner)):
            raise RostoolError(f"metadata {key}.{inner} is missing or not an integer")
    if not _int(body.get("message_count")) or body["message_count"] < 0:
        raise RostoolError("metadata message_count is missing or not a count")
    topics = body.get("topics_with_message_count")
    if not isinstance(topics, list):
        raise RostoolError("metadata topics_with_message_count is missing or not a list")
    for number, entry in enumerate(topics, 1):
        topic = entry.get("topic_metadata") if isinstance(entry, dict) else None
        if not isinstance(topic, dict) or not _int(entry.get("message_count")) or entry["message_count"] < 0:
            raise RostoolError(f"metadata topic entry {number} lacks topic_metadata or a message_count")
        for key in ("name", "type", "serialization_format"):
            if not isinstance(topic.get(key), str) or not topic[key]:
                raise RostoolError(f"metadata topic entry {number}: {key} is missing or not text")
        if topic["serialization_format"] != "cdr":
            raise RostoolError(
                f"metadata topic {topic['name']}: serialization {topic['serialization_format']!r} (not cdr)"
            )
        if not isinstance(topic.get("offered_qos_profiles", ""), (str, list)):
            raise RostoolError(
                f"metadata topic {topic['name']}: offered_qos_profiles is neither text nor a list"
            )
        if not isinstance(topic.get("type_description_hash", ""), str):
            raise RostoolError(f"metadata topic {topic['name']}: type_description_hash is not text")
    mode = body.get("compression_mode") or ""
    form = body.get("compression_format") or ""
    if not isinstance(mode, str) or not isinstance(form, str):
        raise RostoolError("metadata compression_mode/compression_format is not text")
    if mode.lower() not in ("", "none", "file", "message"):
        raise RostoolError(f"unknown metadata compression_mode {mode!r}")
    if mode.lower() in ("file", "message") and form != "zstd":
        raise RostoolError(f"compression format {form!r} is not supported (only zstd)")
    if not isinstance(body.get("files", []), list):
        raise RostoolError("metadata files is not a list")
    return storage, files


def sniff(path: Path) -> BagKind | None:
    """The format of one file from its first bytes; None when it is not a bag file."""
    with path.open("rb") as handle:
        head = handle.read(16)
    if head.startswith(ROS1_MAGIC):
        return "bag"
    if head.startswith(MCAP_MAGIC):
        return "mcap"
    if head.startswith(SQLITE_MAGIC):
        return "db3"
    return None


def detect(given: str | Path) -> BagInput:
    """Classify `given`; raises RostoolError with one clear line when it is not a readable bag."""
    from rostool.bag.bounded import install

    install()  # whatever reads the bag next inflates no chunk past its declared size
    path = Path(given)
    if not path.exists():
        raise RostoolError(f"{path}: no such file or directory")
    if path.is_file() and path.name == "metadata.yaml":
        path = path.parent
    if path.is_dir():
        try:
            return _detect_directory(path)
        except OSError as err:
            raise RostoolError(f"{err.filename or path}: cannot read: {err.strerror or err}") from err
    if not path.is_file():
        raise RostoolError(f"{path}: not a regular file, not a bag")
    try:
        size = path.stat().st_size
        if size == 0:
            raise RostoolError(f"{path}: empty file (0 bytes), not a bag")
        kind = sniff(path)
        with path.open("rb") as handle:
            head = handle.read(16)
    except PermissionError as err:
        raise RostoolError(f"{path}: permission denied") from err
    except OSError as err:
        raise RostoolError(f"{path}: cannot read: {err.strerror or err}") from err
    if kind == "bag":
        if not head.startswith(b"#ROSBAG V2.0\n"):
            version = head[len(ROS1_MAGIC) :].split(b"\n")[0].decode(errors="replace")
            raise RostoolError(f"{path}: ROS 1 bag version {version} is not supported (only 2.0)")
        return BagInput(path, "bag", (path,), "bag")
    if kind is not None:
        return BagInput(path, kind, (path,), "mcap" if kind == "mcap" else "sqlite3")
    if head.startswith(ZSTD_MAGIC):
        raise RostoolError(
            f"{path}: a zstd-compressed storage file; pass the rosbag2 directory that contains it"
        )
    raise RostoolError(f"{path}: not a bag (expected a ROS 1 .bag, an .mcap or .db3 file, or a rosbag2 dir)")


def _detect_directory(path: Path) -> BagInput:
    metadata = path / "metadata.yaml"
    problem = ""
    if metadata.is_file():
        try:
            body = load_metadata(metadata)
            storage, files = check_metadata(body, metadata)
        except MetadataError as err:
            problem = err.problem
        else:
            if str(body.get("compression_mode") or "").lower() != "file":
                kind = "mcap" if storage == "mcap" else "db3"
                for file in files:
                    if file.stat().st_size == 0 or sniff(file) != kind:
                        raise RostoolError(
                            f"{file}: not a valid {kind} file (metadata.yaml: storage {storage})"
                        )
            return BagInput(path, "rosbag2", tuple(files), storage, metadata)
    elif metadata.exists():
        problem = "not a file"
    found = sorted(p for p in path.iterdir() if p.suffix in STORAGE_SUFFIXES and p.is_file())
    if not found:
        if problem:
            raise MetadataError(metadata, f"{problem}; and no .mcap/.db3 files beside it to read instead")
        raise RostoolError(f"{path}: directory has no metadata.yaml and no .mcap/.db3 files, not a bag")
    kinds = {STORAGE_SUFFIXES[p.suffix] for p in found}
    if len(kinds) > 1:
        why = f"{metadata}: {problem}; and" if problem else f"{path}: directory without metadata.yaml"
        raise RostoolError(f"{why} mixes .mcap and .db3 files")
    kind: BagKind = "mcap" if kinds == {"mcap"} else "db3"
    for file in found:
        if file.stat().st_size == 0 or sniff(file) != kind:
            prefix = f"{metadata}: {problem}; and " if problem else ""
            raise RostoolError(f"{prefix}{file}: not a valid {kind} file")
    if problem:
        warn(fallback_warning(metadata, problem, found))
    return BagInput(path, kind, tuple(found), "mcap" if kind == "mcap" else "sqlite3")


def fallback_warning(metadata: Path, problem: str, files: Sequence[Path]) -> str:
    listed = files[0].name if len(files) == 1 else f"{len(files)} {files[0].suffix} files"
    return f"{metadata}: {problem}; reading {listed} beside it instead"


def describe(err: BaseException) -> str:
    """An exception of a library in one line (YAML and zstd errors span several)."""
    text = str(err.args[0]) if err.args and isinstance(err.args[0], str) else str(err)
    text = one_line(text)
    if isinstance(err, MemoryError):
        return "a length field claims more memory than there is (corrupt file?)"
    if isinstance(err, RecursionError):
        return "nesting too deep (corrupt file?)"
    if isinstance(err, OverflowError):
        return f"a length or offset field is out of range (corrupt file?): {text}"
    if not text:
        return type(err).__name__
    if isinstance(err, LookupError) or len(text) <= 3:
        return f"{type(err).__name__}: {text}"
    return text


class guard(AbstractContextManager["guard"]):
    """Turns any failure of the underlying readers on a damaged file into one RostoolError line."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc is None or not isinstance(exc, Exception):
            return
        if isinstance(exc, (RostoolError, BrokenPipeError)):
            return
        text = describe(exc)
        if "not indexed" in text:
            raise RostoolError(
                f"{self.path}: bag is not indexed (its recorder was killed?); run `rostool bag reindex`"
            ) from exc
        cut_short = ("magic", "damaged", "end of file", "Header could not")
        reindexable = self.path.is_file() and self.path.suffix != ".db3"  # reindex knows .bag and .mcap
        if reindexable and any(word in text for word in cut_short):
            text += "; if the file was cut short, `rostool bag reindex` can rebuild it"
        raise RostoolError(f"{self.path}: cannot read bag: {text}") from exc
