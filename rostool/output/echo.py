"""Turns each received or stored message into the text `echo` prints (YAML, JSON or CSV).

One renderer serves `topic echo` and `bag echo`. With several topics in one stream (`several=True`)
each YAML message is preceded by `# TOPIC @ SECONDS` and each JSON line becomes
{"topic", "t", "msg"}; CSV keeps one header per topic.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from rostool.errors import RostoolError
from rostool.output.csv_text import CsvWriter
from rostool.output.json_text import dumps
from rostool.output.plain import TimeStyle, elide, select_field, to_plain
from rostool.output.yaml_text import to_yaml, value_to_yaml

Mode = Literal["yaml", "json", "csv"]


@dataclass
class EchoRenderer:
    mode: Mode = "yaml"
    fields: tuple[str, ...] = ()
    noarr: bool = False
    nostr: bool = False
    style: TimeStyle = "ros1"
    several: bool = False
    _csv: dict[str, CsvWriter] = field(default_factory=dict)

    def render(self, msg: object, time_ns: int, topic: str = "") -> str:
        """The text for one message, without a final newline."""
        if self.noarr or self.nostr:
            msg = elide(msg, self.noarr, self.nostr)
        if self.mode == "csv":
            writer = self._csv.setdefault(topic, CsvWriter())
            if self.fields:
                values = [(path, to_plain(value, self.style)) for path, value in self._selected(msg)]
                return writer.row_values(values, time_ns)
            return writer.row(msg, time_ns)
        if self.mode == "json":
            plain = self._plain(msg)
            if self.several:
                plain = {"topic": topic, "t": time_ns / 1e9, "msg": plain}
            return dumps(plain)
        text = self._yaml(msg) + "\n---"
        if self.several:
            return f"# {topic} @ {time_ns // 1_000_000_000}.{time_ns % 1_000_000_000:09d}\n{text}"
        return text

    def _selected(self, msg: object) -> list[tuple[str, object]]:
        try:
            return [(path, select_field(msg, path)) for path in self.fields]
        except LookupError as err:
            raise RostoolError(f"{err.args[0]}; see the message layout with `rostool msg show`") from err

    def _plain(self, msg: object) -> Any:
        if not self.fields:
            return to_plain(msg, self.style)
        values = self._selected(msg)
        if len(values) == 1:
            return to_plain(values[0][1], self.style)
        return {path: to_plain(value, self.style) for path, value in values}

    def _yaml(self, msg: object) -> str:
        if not self.fields:
            return to_yaml(msg, self.style)
        values = self._selected(msg)
        if len(values) == 1:
            return value_to_yaml(values[0][1], self.style)
        lines = []
        for path, value in values:
            text = value_to_yaml(value, self.style)
            if "\n" in text:
                text = "\n" + "\n".join("  " + line for line in text.splitlines())
            lines.append(f"{path}: {text}")
        return "\n".join(lines)
