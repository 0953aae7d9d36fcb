"""rosbag2's metadata.yaml: read and checked (what the readers need of it, one line for the first
problem), the `bag info` facts it holds, and written (atomically, as a recorder or reindex leaves it)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from rostool.bag.model import BagInfo, BagInput, TopicInfo, TypeInfo
from rostool.errors import RostoolError, one_line, yaml_problem

KEY = "rosbag2_bagfile_information"
METADATA = "metadata.yaml"  # the file that makes a directory a rosbag2 bag
METADATA_TMP = "metadata.yaml.tmp"  # written first, then moved over METADATA


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
    body = info.get(KEY) if isinstance(info, dict) else None
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


def write_metadata(directory: Path, body: dict[str, Any]) -> None:
    """DIR/metadata.yaml holding `body`, replaced in one step (a reader sees the old or the new one)."""
    import yaml

    target = directory / METADATA
    temporary = target.with_name(METADATA_TMP)
    temporary.write_text(yaml.safe_dump({KEY: body}, sort_keys=False))
    os.replace(temporary, target)


def rosbag2_info(bag: BagInput, _freq: bool = False) -> BagInfo:
    """`bag info` of a rosbag2 directory: counts, times and topics as its metadata.yaml states them."""
    assert bag.metadata is not None
    meta = load_metadata(bag.metadata)
    try:
        count = int(meta.get("message_count", 0))
        start = int(meta["starting_time"]["nanoseconds_since_epoch"])
        duration = int(meta["duration"]["nanoseconds"])
        topics, types = [], {}
        for entry in meta.get("topics_with_message_count") or []:
            topic = entry["topic_metadata"]
            serialization = str(topic.get("serialization_format") or "cdr")
            topics.append(
                TopicInfo(
                    str(topic["name"]),
                    str(topic["type"]),
                    int(entry["message_count"]),
                    serialization=serialization,
                )
            )
            digest = str(topic.get("type_description_hash") or "")
            if not types.get(str(topic["type"])):
                types[str(topic["type"])] = digest
    except (KeyError, TypeError, ValueError) as err:
        raise RostoolError(f"{bag.metadata}: incomplete rosbag2 metadata ({describe_key(err)})") from err
    mode = str(meta.get("compression_mode") or "").lower()
    form = str(meta.get("compression_format") or "")
    compression = f"{form} ({mode})" if mode and mode != "none" and form else "none"
    return BagInfo(
        path=str(bag.path),
        format="rosbag2",
        storage=bag.storage,
        version=str(meta.get("version", "")),
        size=bag.size,
        messages=count,
        start_ns=start if count else None,
        end_ns=start + duration if count else None,
        compression=compression,
        types=[TypeInfo(name, digest) for name, digest in sorted(types.items())],
        topics=sorted(topics, key=lambda t: t.name),
        files=[f.name for f in bag.files],
        ros_distro=str(meta.get("ros_distro") or ""),
    )


def describe_key(err: Exception) -> str:
    return f"missing {err}" if isinstance(err, KeyError) else str(err)
