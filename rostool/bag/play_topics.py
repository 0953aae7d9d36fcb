"""What ros2 bag play checks of the bag before playing: the storage `-s` names, and which of the --topics
the bag has."""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence

from rostool.errors import RostoolError


def present_topics(wanted: Sequence[str], in_bag: Collection[str], warn: Callable[[str], None]) -> list[str]:
    """ros2 bag play plays what it can of --topics/--services: names the bag lacks are left out (warned)."""
    present = [t for t in wanted if t in in_bag]
    missing = [t for t in wanted if t not in in_bag]
    if missing and not present:
        have = ", ".join(sorted(in_bag)) or "none"
        raise RostoolError(f"topic {missing[0]} is not in the bag (topics: {have})")
    for name in missing:
        warn(f"{name} is not in the bag; playing the other topics")
    return present


def check_storage(path: str, storage: str | None) -> None:
    """`-s STORAGE` must name the bag's storage (ros2 bag fails to open it otherwise)."""
    if storage is None:
        return
    from rostool.bag.open import detect

    bag = detect(path)
    found = {"db3": "sqlite3"}.get(bag.storage, bag.storage)
    if found != storage:
        raise RostoolError(f"{path}: -s {storage} given, but the bag's storage is {found}")
