"""Input detection: what a path given on the command line is (by content, not by name).

rosbags picks a reader from the file suffix and fails with messages about suffixes; users pass files with
any name, rosbag2 directories without metadata.yaml, or metadata.yaml itself, so this looks at the magic
bytes and the directory contents and says clearly what is wrong when it is not a bag.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rostool.errors import RostoolError

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


def load_metadata(metadata: Path) -> dict[str, Any]:
    """The `rosbag2_bagfile_information` mapping of a metadata.yaml."""
    import yaml

    try:
        info = yaml.load(metadata.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
        body = info["rosbag2_bagfile_information"]
    except (OSError, yaml.YAMLError, KeyError, TypeError) as err:
        raise RostoolError(f"{metadata}: not a valid rosbag2 metadata.yaml ({err})") from err
    if not isinstance(body, dict):
        raise RostoolError(f"{metadata}: not a valid rosbag2 metadata.yaml")
    return body


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
    path = Path(given)
    if not path.exists():
        raise RostoolError(f"{path}: no such file or directory")
    if path.is_file() and path.name == "metadata.yaml":
        path = path.parent
    if path.is_dir():
        return _detect_directory(path)
    try:
        size = path.stat().st_size
        if size == 0:
            raise RostoolError(f"{path}: empty file (0 bytes), not a bag")
        kind = sniff(path)
        with path.open("rb") as handle:
            head = handle.read(16)
    except PermissionError as err:
        raise RostoolError(f"{path}: permission denied") from err
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
    if metadata.is_file():
        info = load_metadata(metadata)
        storage = str(info.get("storage_identifier", ""))
        if storage not in ("mcap", "sqlite3"):
            raise RostoolError(f"{path}: unknown rosbag2 storage {storage!r} (supported: mcap, sqlite3)")
        names = info.get("relative_file_paths") or []
        if not isinstance(names, list):
            raise RostoolError(f"{metadata}: relative_file_paths is not a list")
        files = [path / Path(str(name)).name for name in names]
        missing = [file.name for file in files if not file.exists()]
        if missing:
            listed = ", ".join(missing)
            raise RostoolError(f"{path}: storage files listed in metadata.yaml are missing: {listed}")
        if not files:
            raise RostoolError(f"{path}: metadata.yaml lists no storage files")
        return BagInput(path, "rosbag2", tuple(files), storage, metadata)
    found = sorted(p for p in path.iterdir() if p.suffix in STORAGE_SUFFIXES and p.is_file())
    if not found:
        raise RostoolError(f"{path}: directory has no metadata.yaml and no .mcap/.db3 files, not a bag")
    kinds = {STORAGE_SUFFIXES[p.suffix] for p in found}
    if len(kinds) > 1:
        raise RostoolError(f"{path}: directory without metadata.yaml mixes .mcap and .db3 files")
    kind: BagKind = "mcap" if kinds == {"mcap"} else "db3"
    for file in found:
        if file.stat().st_size == 0 or sniff(file) != kind:
            raise RostoolError(f"{file}: not a valid {kind} file")
    return BagInput(path, kind, tuple(found), "mcap" if kind == "mcap" else "sqlite3")
