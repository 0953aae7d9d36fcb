"""Render reference entries as plain text, Markdown, JSON or a rich table (rich is imported only there)."""

from __future__ import annotations

import json
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from rostool.reference.model import Entry

if TYPE_CHECKING:
    from rich.text import Text

Primary = Literal["ros1", "ros2"]
WIDTH = 100


@dataclass(frozen=True)
class Block:
    """A group of entries shown together: a whole section (with its title) or a list of search hits."""

    title: str | None
    entries: tuple[Entry, ...]


def render_json(entries: Sequence[Entry]) -> str:
    return json.dumps([entry.to_json() for entry in entries], indent=2, ensure_ascii=False)


def render_text(
    blocks: Sequence[Block], notes: Sequence[str], titles: Mapping[str, str], primary: Primary = "ros1"
) -> str:
    lines: list[str] = list(notes)
    if notes:
        lines.append("")
    for block in blocks:
        if block.title is not None:
            lines += [block.title, "=" * len(block.title), ""]
        for entry in block.entries:
            lines += _text_entry(entry, None if block.title else titles.get(entry.section), primary)
            lines.append("")
    return "\n".join(lines).rstrip("\n")


def _text_entry(entry: Entry, section_title: str | None, primary: Primary) -> list[str]:
    heading = (entry.ros2 or "") if primary == "ros2" else entry.ros1
    lines = [f"{heading}  ({section_title})" if section_title else heading]
    lines += textwrap.wrap(entry.description, WIDTH, initial_indent="    ", subsequent_indent="    ")
    # Further rostool forms go on their own lines under the first, without a label of their own.
    forms = rostool_forms(entry, primary) or ("(none)",)
    rostool = [("rostool" if index == 0 else "", form) for index, form in enumerate(forms)]
    fields = [("inputs", entry.inputs), ("output", entry.output)]
    if primary == "ros2":
        # A ROS 2 user looks for the form to type first; the ROS 1 command is background.
        fields += [*rostool, ("ROS 1", entry.ros1)]
    else:
        fields += [("ROS 2", entry.ros2 or "(none)"), *rostool]
    if entry.all_aliases:
        fields.append(("aliases", ", ".join(entry.all_aliases)))
    for label, value in fields:
        lines += textwrap.wrap(
            value,
            WIDTH,
            initial_indent=f"    {label + ':' if label else '':<9}",
            subsequent_indent=" " * 13,
            break_on_hyphens=False,
        )
    return lines


def rostool_forms(entry: Entry, primary: Primary) -> tuple[str, ...]:
    """The entry's rostool forms, the one for the graph the reader asked about first."""
    forms = entry.rostool_forms
    return forms[::-1] if primary == "ros2" else forms


def render_markdown(blocks: Sequence[Block], notes: Sequence[str], titles: Mapping[str, str]) -> str:
    lines = [f"> {_escape(note)}" for note in notes]
    if notes:
        lines.append("")
    for block in blocks:
        with_section = block.title is None
        if block.title is not None:
            lines += [f"## {block.title}", ""]
        header = ["ROS 1", "ROS 2", "rostool", "Description", "Inputs", "Output", "Aliases"]
        if with_section:
            header.insert(0, "Section")
        lines.append("| " + " | ".join(header) + " |")
        lines.append("|" + "---|" * len(header))
        for entry in block.entries:
            cells = [
                _code(entry.ros1),
                _code(entry.ros2),
                "<br>".join(_code(form) for form in entry.rostool_forms),
                _escape(entry.description),
                _escape(entry.inputs),
                _escape(entry.output),
                ", ".join(_code(alias) for alias in entry.all_aliases),
            ]
            if with_section:
                cells.insert(0, _escape(titles.get(entry.section, entry.section)))
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines).rstrip("\n")


def _code(text: str | None) -> str:
    if not text:
        return ""
    fence = "``" if "`" in text else "`"
    return f"{fence}{text.replace('|', chr(92) + '|')}{fence}"


def _escape(text: str) -> str:
    return text.replace("|", "\\|")


def print_table(
    blocks: Sequence[Block], notes: Sequence[str], titles: Mapping[str, str], primary: Primary = "ros1"
) -> None:
    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    console = Console()
    for note in notes:
        console.print(Text(note, style="bold yellow"))
    for block in blocks:
        table = Table(title=block.title, title_justify="left", show_lines=True, expand=True)
        first, second = ("ROS 2", "ROS 1") if primary == "ros2" else ("ROS 1", "ROS 2")
        table.add_column(first, style="bold cyan", overflow="fold", ratio=3)
        table.add_column("What it does", overflow="fold", ratio=4)
        table.add_column(second, overflow="fold", ratio=3)
        table.add_column("rostool", style="green", overflow="fold", ratio=3)
        for entry in block.entries:
            main, other = (entry.ros2, entry.ros1) if primary == "ros2" else (entry.ros1, entry.ros2)
            head = Text(main or "(none)")
            if entry.all_aliases:
                head.append("\nalso: " + ", ".join(entry.all_aliases), style="dim")
            if block.title is None:
                head.append(f"\n[{titles.get(entry.section, entry.section)}]", style="dim italic")
            body = Text(entry.description)
            body.append(f"\nin: {entry.inputs}\nout: {entry.output}", style="dim")
            table.add_row(head, body, Text(other or "(none)"), _rostool_cell(entry, primary))
        console.print(table)


def _rostool_cell(entry: Entry, primary: Primary) -> Text:
    from rich.text import Text

    forms = rostool_forms(entry, primary)
    if not forms:
        return Text("(none)")
    cell = Text(forms[0], style="bold")
    for form in forms[1:]:
        cell.append("\n" + form, style="dim")
    return cell
