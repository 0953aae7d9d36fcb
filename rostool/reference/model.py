"""Load and validate the command reference (rostool/data/cheatsheet.yaml) into typed objects."""

from __future__ import annotations

import re
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import click
import yaml

from rostool.errors import RostoolError

ENTRY_KEYS = frozenset(
    {"ros1", "description", "inputs", "output", "ros2", "rostool", "rostool_ros2", "aliases", "keywords"}
)
REQUIRED_ENTRY_KEYS = frozenset({"ros1", "description", "inputs", "output", "ros2", "rostool"})
MISSPELLING_KEYS = frozenset({"wrong", "right", "entry", "what", "kind", "problem", "why", "match"})
REQUIRED_MISSPELLING_KEYS = frozenset({"wrong", "right", "entry", "what", "kind"})
MISSPELLING_KINDS = frozenset({"command", "name"})
ROS2_PREFIX = ("rostool", "--ros2")


class CheatsheetDataError(RostoolError):
    """The reference file is malformed (a packaging or editing mistake, not a user error)."""


@dataclass(frozen=True)
class Entry:
    section: str
    ros1: str
    description: str
    inputs: str
    output: str
    ros2: str | None
    # The rostool form as shown: None when there is none or its command group is not built yet.
    rostool: str | None
    # The rostool form as written in the data file, before hiding unbuilt groups.
    planned_rostool: str | None
    # The rostool form for a ROS 2 graph (`rostool --ros2 ...`, ros2cli's argument order), shown and
    # as written, the same way.
    rostool_ros2: str | None = None
    planned_rostool_ros2: str | None = None
    aliases: tuple[str, ...] = ()
    misspellings: tuple[str, ...] = ()
    keywords: tuple[str, ...] = ()

    @property
    def all_aliases(self) -> tuple[str, ...]:
        """The book's wrong forms first, then the other common spellings."""
        return self.misspellings + self.aliases

    @property
    def rostool_forms(self) -> tuple[str, ...]:
        """The shown rostool forms: the plain one, then the ROS 2 one."""
        return tuple(form for form in (self.rostool, self.rostool_ros2) if form is not None)

    @property
    def planned_rostool_forms(self) -> tuple[str, ...]:
        return tuple(form for form in (self.planned_rostool, self.planned_rostool_ros2) if form is not None)

    def to_json(self) -> dict[str, Any]:
        return {
            "section": self.section,
            "ros1": self.ros1,
            "ros2": self.ros2,
            "rostool": self.rostool,
            "rostool_ros2": self.rostool_ros2,
            "description": self.description,
            "inputs": self.inputs,
            "output": self.output,
            "aliases": list(self.all_aliases),
        }


@dataclass(frozen=True)
class Section:
    id: str
    title: str
    entries: tuple[Entry, ...]


@dataclass(frozen=True)
class Misspelling:
    """A wrong form printed in the book and the correction it gets."""

    wrong: str
    right: str
    entry: str  # ros1 form of the entry the wrong form resolves to
    what: str  # "command", "topic name", ...
    kind: str  # "command": matched at the start of a query; "name": matched anywhere
    problem: str = "a misspelling in the book"
    why: str | None = None
    match: re.Pattern[str] | None = None

    def note(self, wrong: str | None = None, right: str | None = None) -> str:
        text = f"note: '{wrong or self.wrong}' is {self.problem}; the {self.what} is '{right or self.right}'"
        return f"{text} ({self.why})" if self.why else text


@dataclass(frozen=True)
class Reference:
    sections: tuple[Section, ...]
    misspellings: tuple[Misspelling, ...] = field(default=())

    @property
    def entries(self) -> tuple[Entry, ...]:
        return tuple(entry for section in self.sections for entry in section.entries)

    @property
    def section_ids(self) -> tuple[str, ...]:
        return tuple(section.id for section in self.sections)

    def section(self, name: str) -> Section:
        """The section with this id or title (case-insensitive); RostoolError listing valid ones if none."""
        wanted = name.strip().lower()
        for section in self.sections:
            if wanted in (section.id.lower(), section.title.lower()):
                return section
        raise RostoolError(
            f"unknown section '{name}'; valid sections: {', '.join(self.section_ids)}", exit_code=2
        )

    def entry(self, ros1: str) -> Entry | None:
        for entry in self.iter_entries():
            if entry.ros1 == ros1:
                return entry
        return None

    def iter_entries(self) -> Iterator[Entry]:
        for section in self.sections:
            yield from section.entries


def data_path() -> Path:
    return Path(str(resources.files("rostool") / "data" / "cheatsheet.yaml"))


def live_command_groups(root: click.Group) -> frozenset[str]:
    """Top-level rostool verbs (of the root group `root`) whose modules exist now (checked without
    importing them)."""
    return frozenset(root.list_commands(click.Context(root, info_name="rostool")))


@lru_cache(maxsize=1)
def default_reference(available_groups: frozenset[str]) -> Reference:
    return load_reference(available_groups=available_groups)


def load_reference(path: Path | None = None, *, available_groups: Collection[str]) -> Reference:
    """Read, validate and build the reference.

    `available_groups` are the top-level rostool verbs that exist (`live_command_groups(root)`); rostool
    forms naming any other group are hidden, since that group has not landed yet.
    """
    source = path or data_path()
    try:
        text = source.read_text(encoding="utf-8")
    except OSError as err:
        raise CheatsheetDataError(f"cannot read {source}: {err.strerror}; reinstall rostool") from err
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        raw = yaml.load(text, Loader=loader)
    except yaml.YAMLError as err:
        raise CheatsheetDataError(f"{source} is not valid YAML: {err}") from err
    return build_reference(raw, frozenset(available_groups), origin=str(source))


def build_reference(raw: object, available_groups: Collection[str], origin: str = "cheatsheet") -> Reference:
    problems: list[str] = []
    if not isinstance(raw, Mapping) or not isinstance(raw.get("sections"), list):
        raise CheatsheetDataError(f"{origin}: top level must be a mapping with a 'sections' list")
    misspellings = _parse_misspellings(raw.get("misspellings") or [], problems)
    by_entry: dict[str, list[str]] = {}
    for misspelling in misspellings:
        by_entry.setdefault(misspelling.entry, []).append(misspelling.wrong)

    sections: list[Section] = []
    seen_sections: set[str] = set()
    seen_ros1: set[str] = set()
    for index, raw_section in enumerate(raw["sections"]):
        where = f"sections[{index}]"
        if not isinstance(raw_section, Mapping):
            problems.append(f"{where}: must be a mapping")
            continue
        section_id = _string(raw_section, "id", where, problems)
        title = _string(raw_section, "title", where, problems)
        if section_id in seen_sections:
            problems.append(f"{where}: duplicate section id '{section_id}'")
        seen_sections.add(section_id)
        raw_entries = raw_section.get("entries")
        if not isinstance(raw_entries, list) or not raw_entries:
            problems.append(f"{where}: 'entries' must be a non-empty list")
            continue
        entries = []
        for position, raw_entry in enumerate(raw_entries):
            entry = _parse_entry(
                raw_entry, section_id, f"{where}.entries[{position}]", by_entry, available_groups, problems
            )
            if entry is None:
                continue
            if entry.ros1 in seen_ros1:
                problems.append(f"duplicate ros1 form '{entry.ros1}'")
            seen_ros1.add(entry.ros1)
            entries.append(entry)
        sections.append(Section(section_id, title, tuple(entries)))

    for misspelling in misspellings:
        if misspelling.entry not in seen_ros1:
            problems.append(
                f"misspelling '{misspelling.wrong}' points at unknown entry '{misspelling.entry}'"
            )
    _check_alias_clashes(sections, problems)
    if problems:
        shown = "; ".join(problems[:5]) + (f"; and {len(problems) - 5} more" if len(problems) > 5 else "")
        raise CheatsheetDataError(f"{origin} is invalid: {shown}")
    return Reference(tuple(sections), tuple(misspellings))


def _parse_entry(
    raw: object,
    section_id: str,
    where: str,
    misspellings_by_entry: Mapping[str, list[str]],
    available_groups: Collection[str],
    problems: list[str],
) -> Entry | None:
    if not isinstance(raw, Mapping):
        problems.append(f"{where}: must be a mapping")
        return None
    missing = REQUIRED_ENTRY_KEYS - raw.keys()
    unknown = raw.keys() - ENTRY_KEYS
    if missing:
        problems.append(f"{where}: missing {', '.join(sorted(missing))}")
        return None
    if unknown:
        problems.append(f"{where}: unknown keys {', '.join(sorted(map(str, unknown)))}")
    ros1 = _string(raw, "ros1", where, problems)
    planned = _rostool_form(raw, "rostool", ("rostool",), where, problems)
    planned_ros2 = _rostool_form(raw, "rostool_ros2", ROS2_PREFIX, where, problems)
    return Entry(
        section=section_id,
        ros1=ros1,
        description=_string(raw, "description", where, problems),
        inputs=_string(raw, "inputs", where, problems),
        output=_string(raw, "output", where, problems),
        ros2=_optional_string(raw, "ros2", where, problems),
        rostool=_shown(planned, available_groups),
        planned_rostool=planned,
        rostool_ros2=_shown(planned_ros2, available_groups),
        planned_rostool_ros2=planned_ros2,
        aliases=_string_list(raw, "aliases", where, problems),
        misspellings=tuple(misspellings_by_entry.get(ros1, ())),
        keywords=_string_list(raw, "keywords", where, problems),
    )


def _rostool_form(
    raw: Mapping[str, Any], key: str, prefix: tuple[str, ...], where: str, problems: list[str]
) -> str | None:
    """The form under `key`, or None (with a problem) unless it is `<prefix> <verb> ...`."""
    form = _optional_string(raw, key, where, problems)
    if form is None:
        return None
    words = form.split()
    if len(words) <= len(prefix) or tuple(words[: len(prefix)]) != prefix or words[len(prefix)][0] == "-":
        problems.append(f"{where}: {key} form '{form}' must start with '{' '.join(prefix)} <verb>'")
        return None
    return form


def form_group(form: str) -> str:
    """The top-level verb a rostool form runs: its first word after `rostool` and root options."""
    return next(word for word in form.split()[1:] if not word.startswith("-"))


def _shown(planned: str | None, available_groups: Collection[str]) -> str | None:
    return planned if planned is not None and form_group(planned) in available_groups else None


def _parse_misspellings(raw: object, problems: list[str]) -> list[Misspelling]:
    if not isinstance(raw, list):
        problems.append("'misspellings' must be a list")
        return []
    result = []
    seen: set[str] = set()
    for index, item in enumerate(raw):
        where = f"misspellings[{index}]"
        if not isinstance(item, Mapping):
            problems.append(f"{where}: must be a mapping")
            continue
        missing = REQUIRED_MISSPELLING_KEYS - item.keys()
        if missing:
            problems.append(f"{where}: missing {', '.join(sorted(missing))}")
            continue
        if item.keys() - MISSPELLING_KEYS:
            problems.append(
                f"{where}: unknown keys {', '.join(sorted(map(str, item.keys() - MISSPELLING_KEYS)))}"
            )
        kind = _string(item, "kind", where, problems)
        if kind not in MISSPELLING_KINDS:
            problems.append(f"{where}: kind must be one of {', '.join(sorted(MISSPELLING_KINDS))}")
        pattern = None
        if item.get("match") is not None:
            try:
                pattern = re.compile(str(item["match"]), re.IGNORECASE)
            except re.error as err:
                problems.append(f"{where}: bad match pattern: {err}")
        wrong = _string(item, "wrong", where, problems)
        if wrong in seen:
            problems.append(f"{where}: duplicate wrong form '{wrong}'")
        seen.add(wrong)
        result.append(
            Misspelling(
                wrong=wrong,
                right=_string(item, "right", where, problems),
                entry=_string(item, "entry", where, problems),
                what=_string(item, "what", where, problems),
                kind=kind,
                problem=str(item.get("problem") or "a misspelling in the book"),
                why=_optional_string(item, "why", where, problems),
                match=pattern,
            )
        )
    return result


def _check_alias_clashes(sections: list[Section], problems: list[str]) -> None:
    """An alias must lead to exactly one entry and must not be another entry's own ros1 form."""
    ros1_forms = {entry.ros1 for section in sections for entry in section.entries}
    owner: dict[str, str] = {}
    for section in sections:
        for entry in section.entries:
            for alias in entry.aliases:
                if alias in ros1_forms:
                    problems.append(f"alias '{alias}' of '{entry.ros1}' is itself an entry")
                if alias in owner and owner[alias] != entry.ros1:
                    problems.append(f"alias '{alias}' belongs to both '{owner[alias]}' and '{entry.ros1}'")
                owner[alias] = entry.ros1


def _string(raw: Mapping[str, Any], key: str, where: str, problems: list[str]) -> str:
    value = raw.get(key)
    if not isinstance(value, str) or not value.strip():
        problems.append(f"{where}: '{key}' must be a non-empty string")
        return ""
    return " ".join(value.split())


def _optional_string(raw: Mapping[str, Any], key: str, where: str, problems: list[str]) -> str | None:
    if raw.get(key) is None:
        return None
    return _string(raw, key, where, problems)


def _string_list(raw: Mapping[str, Any], key: str, where: str, problems: list[str]) -> tuple[str, ...]:
    value = raw.get(key)
    if value is None:
        return ()
    if not isinstance(value, list) or not all(isinstance(item, str) and item.strip() for item in value):
        problems.append(f"{where}: '{key}' must be a list of non-empty strings")
        return ()
    return tuple(" ".join(item.split()) for item in value)
