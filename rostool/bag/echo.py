"""`bag echo`'s engine: one bag's messages rendered as text, or several bags in parallel processes printed
in the bags' order."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal, TextIO

from rostool.bag.many import BagItem
from rostool.bag.message_filter import message_filter
from rostool.errors import RostoolError


@dataclass(frozen=True)
class EchoSettings:
    topics: tuple[str, ...]
    count: int | None
    mode: Literal["yaml", "json", "csv"]
    fields: tuple[str, ...]
    noarr: bool
    nostr: bool
    expr: str | None
    start: str | None
    end: str | None
    distro: str


def echo_bag(path: Any, settings: EchoSettings, write: Callable[[str], Any], bag_name: str | None) -> None:
    """Print one bag; `bag_name` is set when it is one of several (JSON lines then name it)."""
    from rostool.bag.convert import parse_time
    from rostool.bag.reader import BagReader
    from rostool.output.echo import EchoRenderer
    from rostool.output.json_text import dumps

    with BagReader([path], settings.distro) as reader:
        if bag_name is not None and settings.topics:  # a fleet: a topic some bags lack is not an error
            conns = reader.select([name for name in settings.topics if name in reader.topics])
            conns = conns if any(name in reader.topics for name in settings.topics) else []
        else:
            conns = reader.select(settings.topics)
        names = sorted({c.topic for c in conns})
        several = len(names) > 1 or bag_name is not None
        if settings.mode == "csv" and several and not settings.fields:
            raise RostoolError("--csv prints one topic: name it (e.g. `rostool bag echo BAG /topic --csv`)")
        render = EchoRenderer(
            settings.mode,
            settings.fields,
            settings.noarr,
            settings.nostr,
            style="ros1" if reader.ros_version == 1 else "ros2",
            several=several,
        )
        prefix = ""
        if bag_name is not None:
            if settings.mode == "json":
                prefix = '{"bag": ' + dumps(bag_name) + ", "
            else:
                write(f"# bag: {path}\n")
        keep = message_filter(settings.expr)
        first = parse_time(settings.start, reader.start_ns, "start")
        last = parse_time(settings.end, reader.start_ns, "end")
        printed = 0
        for conn, timestamp, data in reader.messages(conns, first, last) if conns else ():
            msg = reader.deserialize(data, conn)
            if keep is not None and not keep(msg, conn.topic, timestamp):
                continue
            text = render.render(msg, timestamp, conn.topic)
            write((prefix + text[1:] if prefix else text) + "\n")
            printed += 1
            if settings.count is not None and printed >= settings.count:
                break


def echo_many(items: Sequence[BagItem], settings: EchoSettings, jobs: int | None, out: TextIO) -> None:
    """Each bag is printed into a file by a worker; the files are copied to `out` in the bags' order."""
    import shutil
    import tempfile
    from functools import partial

    from rostool.bag.many import successes

    with tempfile.TemporaryDirectory(prefix="rostool-echo-") as folder:
        work = partial(_echo_to_file, settings, folder)
        # no bar when the messages go to the same terminal: it would cut through them
        for _item, text_path in successes(work, items, jobs, "reading", bar=not out.isatty()):
            with open(text_path, encoding="utf-8") as handle:
                shutil.copyfileobj(handle, out)
            os.unlink(text_path)
        out.flush()


def _echo_to_file(settings: EchoSettings, folder: str, item: BagItem) -> str:
    path = os.path.join(folder, f"{item.name}.txt")
    with open(path, "w", encoding="utf-8") as handle:
        echo_bag(item.path, settings, handle.write, item.name)
    return path
