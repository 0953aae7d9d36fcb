"""Turns each received or stored message into the text `echo` prints (YAML, JSON or CSV)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

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
    _csv: CsvWriter = field(default_factory=CsvWriter)

    def render(self, msg: object, time_ns: int) -> str:
        if self.noarr or self.nostr:
            msg = elide(msg, self.noarr, self.nostr)
        if self.fields:
            return self._render_fields(msg, time_ns)
        if self.mode == "json":
            return dumps(to_plain(msg, self.style))
        if self.mode == "csv":
            return self._csv.row(msg, time_ns)
        return to_yaml(msg, self.style) + "\n---"

    def _render_fields(self, msg: object, time_ns: int) -> str:
        try:
            values = [(path, select_field(msg, path)) for path in self.fields]
        except LookupError as err:
            raise RostoolError(f"{err}; see the message layout with `rostool msg show`") from err
        if self.mode == "json":
            if len(values) == 1:
                return dumps(to_plain(values[0][1], self.style))
            return dumps({path: to_plain(value, self.style) for path, value in values})
        if self.mode == "csv":
            return self._csv.row_values([(path, to_plain(v, self.style)) for path, v in values], time_ns)
        if len(values) == 1:
            return value_to_yaml(values[0][1], self.style) + "\n---"
        lines = []
        for path, value in values:
            text = value_to_yaml(value, self.style)
            joined = f"{path}:\n" + _indent(text) if "\n" in text else f"{path}: {text}"
            lines.append(joined)
        return "\n".join(lines) + "\n---"


def _indent(text: str) -> str:
    return "\n".join("  " + line for line in text.splitlines())
