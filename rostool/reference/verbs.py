"""Check that the reference's rostool forms (plain and ROS 2) name verbs and flags that exist."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import click

from rostool.reference.model import Reference

# The command tree the project plans (issue tracker); groups land one by one. None: a leaf verb.
PLANNED_TREE: Mapping[str, frozenset[str] | None] = {
    "core": None,
    "console": frozenset({"echo", "list", "get", "set"}),
    "lifecycle": frozenset({"nodes", "get", "list", "set"}),
    "node": frozenset({"list", "info", "ping", "kill"}),
    "topic": frozenset({"list", "info", "type", "find", "echo", "hz", "bw", "delay", "pub"}),
    "param": frozenset({"list", "get", "set", "describe", "delete", "dump", "load"}),
    "msg": frozenset({"show", "list", "md5"}),
    "srv": frozenset({"show", "list"}),
    "interface": frozenset({"list", "package", "packages", "proto", "show"}),
    "service": frozenset({"list", "type", "info", "uri", "find", "call", "echo"}),
    "action": frozenset({"list", "info", "type", "find", "send-goal", "send_goal", "cancel"}),
    "bag": frozenset({"info", "play", "record", "convert", "echo", "filter", "reindex", "burst"}),
    "daemon": frozenset({"start", "stop", "status"}),
    "cheatsheet": None,
}


@dataclass(frozen=True)
class Resolved:
    """How far a form's words resolve in a click tree."""

    command: click.Command  # the last command reached (a leaf, or the group that lacked a subcommand)
    path: tuple[str, ...]  # the words naming it, from `rostool`
    arguments: tuple[str, ...]  # the words after the leaf: its arguments and flags
    problem: str | None = None  # a subcommand or a group option that does not exist


def resolve(form: str, root: click.Command) -> Resolved:
    """Walk `form` down the tree: while the current command is a group, a flag must be one of the
    group's options (`rostool --ros2 ...`) and any other word must name a subcommand."""
    from types import SimpleNamespace

    # The version a form is written for chooses the verb (`bag record` has ROS 2 forms): --ros2 or ROS 1.
    version = 2 if "--ros2" in form.split() else 1
    ctx = click.Context(root, info_name="rostool", obj=SimpleNamespace(ros_version=version))
    command, path = root, ("rostool",)
    words = form.split()[1:]
    while words and isinstance(command, click.Group):
        word, words = words[0], words[1:]
        if word.startswith("-"):
            if word not in _options(command):
                return Resolved(command, path, (), f"'{' '.join(path)}' has no option {word}")
            path = (*path, word)
            continue
        sub = command.get_command(ctx, word)
        if sub is None:
            return Resolved(command, path, (), f"'{' '.join(path)}' has no subcommand '{word}'")
        command, path = sub, (*path, word)
    return Resolved(command, path, tuple(words))


def missing_rostool_verbs(reference: Reference, root: click.Command) -> list[str]:
    """Problems with the shown rostool forms, resolved against the click tree `root` (rostool's own).

    Each word after `rostool` must name a subcommand (or an option of the group) for as long as the
    current command is a group; once a leaf command is reached the remaining words are its arguments
    and flags.
    """
    problems = []
    for entry in reference.iter_entries():
        for form in entry.rostool_forms:
            problem = resolve(form, root).problem
            if problem is not None:
                problems.append(f"{entry.ros1}: {problem}")
    return problems


def unknown_rostool_flags(reference: Reference, root: click.Command) -> list[str]:
    """Flags in shown rostool forms that the resolved leaf command does not accept."""
    problems = []
    for entry in reference.iter_entries():
        for form in entry.rostool_forms:
            resolved = resolve(form, root)
            if resolved.problem is not None or isinstance(resolved.command, click.Group):
                continue
            accepted, name = _options(resolved.command), resolved.command.name
            for word in resolved.arguments:
                if word.startswith("-") and word not in accepted:
                    problems.append(f"{entry.ros1}: '{form}' uses {word}, which {name} lacks")
    return problems


def unplanned_rostool_verbs(reference: Reference) -> list[str]:
    """rostool forms (shown or still hidden) that name a verb outside the planned tree."""
    problems = []
    for entry in reference.iter_entries():
        for form in entry.planned_rostool_forms:
            words = [word for word in form.split()[1:] if not word.startswith("-")]
            group = words[0]
            if group not in PLANNED_TREE:
                problems.append(f"{entry.ros1}: no planned rostool group '{group}'")
                continue
            subcommands = PLANNED_TREE[group]
            if subcommands is not None and (len(words) < 2 or words[1] not in subcommands):
                problems.append(f"{entry.ros1}: no planned verb 'rostool {' '.join(words[:2])}'")
    return problems


def _options(command: click.Command) -> frozenset[str]:
    return frozenset(opt for param in command.params for opt in (*param.opts, *param.secondary_opts))
