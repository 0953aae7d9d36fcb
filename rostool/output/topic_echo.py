"""What `topic echo` prints for each live message: rostopic's YAML/JSON/CSV (the shared `EchoRenderer`), or
ros2 topic echo's text (truncation, flow style, --raw bytes) when the graph follows ROS 2's style."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rostool.errors import RostoolError
from rostool.output import ros2_echo
from rostool.output.echo import EchoRenderer, Mode
from rostool.output.plain import TimeStyle, select_field

Render = Callable[[Any, Any], str]  # (received, decoded message) -> the text to print


@dataclass(frozen=True)
class EchoForm:
    """echo's output flags."""

    fields: tuple[str, ...] = ()
    as_json: bool = False
    as_csv: bool = False
    noarr: bool = False
    nostr: bool = False
    truncate_length: int | None = None
    full_length: bool = False
    flow_style: bool = False
    raw: bool = False


def field_lookup(types: Any) -> ros2_echo.Lookup:
    """The field descriptions of a graph's type store (`types.store.fielddefs`), for ROS 2's forms."""
    return ros2_echo.fielddefs_lookup(getattr(getattr(types, "store", None), "fielddefs", {}))


def echo_renderer(style: TimeStyle, types: Any, form: EchoForm) -> Render:
    """(received, decoded message) -> the text to print, in the style's form."""
    if form.raw:
        return lambda received, _message: f"{bytes(received.payload)!r}\n---"
    mode: Mode = "json" if form.as_json else "csv" if form.as_csv else "yaml"
    for path in form.fields if style == "ros2" else ():
        if not path.strip(". "):
            raise RostoolError(f"Invalid field value '{path}'")
    if style == "ros2" and not form.as_json:
        opts = ros2_echo.Ros2EchoOptions(
            None if form.full_length else 128 if form.truncate_length is None else form.truncate_length,
            form.noarr,
            form.nostr,
            form.flow_style,
        )
        return functools.partial(_ros2_text, form.fields, form.as_csv, opts, field_lookup(types))
    renderer = EchoRenderer(mode, form.fields, form.noarr, form.nostr, style=style)
    return lambda received, message: renderer.render(message, received.recv_time_ns)


def _ros2_text(
    fields: tuple[str, ...], as_csv: bool, opts: Any, lookup: Any, _received: Any, message: Any
) -> str:
    if not fields:
        if as_csv:
            return ros2_echo.to_csv(message, opts, lookup)
        return ros2_echo.to_yaml(message, opts, lookup) + "\n---"
    texts = []
    for path in fields:
        try:
            value = select_field(message, path)
        except LookupError as err:
            part = str(err).split("'")[1] if "'" in str(err) else path
            kind = type(message).__name__.split("__")[-1]
            raise RostoolError(f"Invalid field '{path}': '{kind}' object has no attribute '{part}'") from err
        texts.append(
            ros2_echo.to_csv(value, opts, lookup) if as_csv else ros2_echo.field_text(value, opts, lookup)
        )
    return ("," if as_csv else "\n").join(texts) + ("" if as_csv else "\n---")
