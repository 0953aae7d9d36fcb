"""rosbag2's --static-topics-path YAML: topics recorded with a type given up front, subscribed at once instead
of after a publisher is discovered (rosbag2 PR 2319):

    static_topics_and_types_list:
      - [/topic_name1, std_msgs/msg/String]
      - [/topic_name2, sensor_msgs/msg/Imu]

rosbag2 logs a bad file and records without it; rostool refuses it in one line before anything is written.
The types are checked against the graph's type store by the recorder (the backend knows which it has)."""

from __future__ import annotations

from pathlib import Path

from rostool.errors import RostoolError

KEY = "static_topics_and_types_list"


def load_static_topics(path: str) -> dict[str, str]:
    """topic -> type, in the file's order; a missing, unreadable or misshapen file is one line."""
    import yaml

    flag = f"--static-topics-path {path}"
    try:
        data = yaml.safe_load(Path(path).read_text())
    except FileNotFoundError as err:
        raise RostoolError(f"{flag}: no such file") from err
    except (OSError, UnicodeDecodeError) as err:
        raise RostoolError(f"{flag}: cannot read it: {err}") from err
    except yaml.YAMLError as err:
        mark, problem = getattr(err, "problem_mark", None), getattr(err, "problem", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        raise RostoolError(f"{flag}: not YAML: {where}{problem or err}") from err
    if not isinstance(data, dict) or KEY not in data:
        raise RostoolError(f"{flag}: Static topics YAML file must have top-level key '{KEY}'")
    entries = data[KEY]
    if not isinstance(entries, list):
        raise RostoolError(
            f"{flag}: Top-level key '{KEY}' must contain a list of 'topic_name, topic_type' pairs"
        )
    found: dict[str, str] = {}
    for number, entry in enumerate(entries, 1):
        if not (isinstance(entry, list) and len(entry) == 2 and all(isinstance(v, str) for v in entry)):
            raise RostoolError(
                f"{flag}: entry {number} ({entry!r}) is not a [topic_name, topic_type] pair, "
                "e.g. [/chatter, std_msgs/msg/String]"
            )
        topic, type_name = (value.strip() for value in entry)
        if not topic or any(c.isspace() for c in topic):
            raise RostoolError(f"{flag}: entry {number}: {entry[0]!r} is not a topic name")
        if not type_name:
            raise RostoolError(f"{flag}: Static topic {topic} has no corresponding type")
        if found.setdefault(topic, type_name) != type_name:
            raise RostoolError(f"{flag}: {topic} is listed with two types, {found[topic]} and {type_name}")
    if not found:
        raise RostoolError(f"{flag}: '{KEY}' lists no topics")
    return found
