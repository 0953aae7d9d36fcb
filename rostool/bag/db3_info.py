"""`bag info` of .db3 files: the topics table plus one GROUP BY over the message rows (SQLite skips the
blob overflow pages, so the messages themselves are not read)."""

from __future__ import annotations

from collections import Counter

from rostool.bag.failures import describe
from rostool.bag.model import BagInfo, BagInput, TopicInfo, TypeInfo
from rostool.errors import RostoolError


def db3_info(bag: BagInput, _freq: bool = False) -> BagInfo:
    import sqlite3

    counts: Counter[str] = Counter()
    types: dict[str, str] = {}
    topic_types: dict[str, str] = {}
    start: int | None = None
    end: int | None = None
    version = ""
    distro = ""
    for path in bag.files:
        try:
            db = sqlite3.connect(f"file:{path}?mode=ro&immutable=1", uri=True)
        except sqlite3.Error as err:
            raise RostoolError(f"{path}: cannot open database: {describe(err)}") from err
        db.text_factory = lambda raw: raw.decode("utf-8", errors="replace")  # damaged text stays readable
        try:
            tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
            if not {"messages", "topics"} <= tables:
                raise RostoolError(f"{path}: not a rosbag2 database (no messages/topics tables)")
            if "schema" in tables:
                row = db.execute("SELECT schema_version FROM schema").fetchone()
                version = f"sqlite3 schema {row[0]}" if row else version
                if row and "ros_distro" in {r[1] for r in db.execute("PRAGMA table_info(schema)")}:
                    distro = str(db.execute("SELECT ros_distro FROM schema").fetchone()[0] or "")
            columns = {row[1] for row in db.execute("PRAGMA table_info(topics)")}
            hash_column = "type_description_hash" if "type_description_hash" in columns else "''"
            names = {}
            for tid, name, typ, digest in db.execute(f"SELECT id, name, type, {hash_column} FROM topics"):
                if not isinstance(name, str) or not isinstance(typ, str):
                    raise RostoolError(f"{path}: damaged database: topic {tid} has no name or no type")
                names[tid] = name
                topic_types.setdefault(name, typ)
                if not types.get(typ):
                    types[typ] = digest if isinstance(digest, str) else ""
            for tid, count, lo, hi in db.execute(
                "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id"
            ):
                if not all(isinstance(value, int) for value in (count, lo, hi)):
                    raise RostoolError(f"{path}: damaged database: message timestamps are not integers")
                counts[names.get(tid, f"<topic id {tid}>")] += count
                start = lo if start is None else min(start, lo)
                end = hi if end is None else max(end, hi)
        except sqlite3.Error as err:
            raise RostoolError(f"{path}: cannot read database: {describe(err)}") from err
        finally:
            db.close()
    return BagInfo(
        path=str(bag.path),
        format="db3",
        storage="sqlite3",
        version=version or "sqlite3",
        size=bag.size,
        messages=sum(counts.values()),
        start_ns=start,
        end_ns=end,
        types=[TypeInfo(name, digest) for name, digest in sorted(types.items())],
        topics=[TopicInfo(name, topic_types.get(name, ""), counts[name]) for name in sorted(topic_types)],
        files=[f.name for f in bag.files] if len(bag.files) > 1 else [],
        ros_distro=distro,
    )
