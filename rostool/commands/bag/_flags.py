"""How the record and play verbs read their flags.

ros2 bag's list options take several values (`--topics a b c`); click options take one, so `ListCommand`
rewrites `--topics a b c` into `--topics a --topics b --topics c` before parsing (up to the next `-x`).
`parsed_into` hands a verb its options as one typed, frozen dataclass instead of twenty to fifty keywords.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click

Flags = TypeVar("Flags")


class ListCommand(click.Command):
    """A click command whose `list_options` take every value up to the next option, as argparse's nargs='+'.

    `optional_values`: options whose value may be left out (`--clock` alone means `--clock=40`).
    `bag_last`: play's BAG may follow a list (`--topics /a /b BAG`): an existing path ends the list.
    """

    def __init__(
        self,
        *args: Any,
        list_options: Sequence[str] = (),
        optional_values: dict[str, str] | None = None,
        bag_last: bool = False,
        **kwargs: Any,
    ) -> None:
        super().__init__(*args, **kwargs)
        self.list_options = set(list_options)
        self.optional_values = optional_values or {}
        self.bag_last = bag_last

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        return super().parse_args(ctx, self._expand(args))

    def _expand(self, args: list[str]) -> list[str]:
        out: list[str] = []
        i = 0
        while i < len(args):
            arg = args[i]
            i += 1
            if arg == "--":
                out += args[i - 1 :]
                break
            if arg in self.optional_values:
                value = args[i] if i < len(args) else None
                if value is not None and _is_number(value):
                    out.append(f"{arg}={value}")
                    i += 1
                else:
                    out.append(f"{arg}={self.optional_values[arg]}")
                continue
            if arg not in self.list_options:
                out.append(arg)
                continue
            values = []
            while i < len(args) and not (args[i].startswith("-") and len(args[i]) > 1):
                values.append(args[i])
                i += 1
            bag_given = any(Path(a).exists() for a in out if not a.startswith("-"))
            if self.bag_last and values and i == len(args) and not bag_given and Path(values[-1]).exists():
                out.append(values.pop())  # `--topics /a /b BAG`: the bag ends the list
            for value in values:
                out += [arg, value]
        return out


def _is_number(text: str) -> bool:
    try:
        return float(text) is not None
    except ValueError:
        return False


def parsed_into(
    flags_type: Callable[..., Flags],
) -> Callable[[Callable[[click.Context, Flags], None]], Callable[..., None]]:
    """The verb gets `(ctx, flags_type(**options))`: the dataclass's fields are the click parameters' names,
    so an option without a field (or a field without an option) fails at once."""

    def decorate(verb: Callable[[click.Context, Flags], None]) -> Callable[..., None]:
        @functools.wraps(verb)
        def callback(**options: Any) -> None:
            verb(click.get_current_context(), flags_type(**options))

        return callback

    return decorate
