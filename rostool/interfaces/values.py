"""Command-line values (YAML text) -> Python values, with safe_load only."""

from __future__ import annotations

from typing import Any

import yaml

from rostool.errors import RostoolError


def parse_yaml(text: str, what: str = "value") -> Any:
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise RostoolError(f"invalid YAML in {what}{where}: {problem}") from err


def call_args(args: tuple[str, ...]) -> list[Any]:
    """Command-line values as `rosservice call` reads them: each one YAML, an empty one is ''."""
    return [parse_yaml(arg or "''", f"value {index + 1}") for index, arg in enumerate(args)]


def message_args(args: tuple[str, ...]) -> Any:
    """`rostopic pub` argument rules: one YAML mapping, or positional field values."""
    if not args:
        return {}
    if len(args) == 1:
        return parse_yaml(args[0], "the message value")
    return [parse_yaml(arg, f"value {index + 1}") for index, arg in enumerate(args)]
