"""Check that the reference's rostool forms name verbs that exist."""

from __future__ import annotations

from collections.abc import Mapping

import click

from rostool.reference.model import Reference

# The command tree the project plans (issue tracker); groups land one by one. None: a leaf verb.
PLANNED_TREE: Mapping[str, frozenset[str] | None] = {
    "core": None,
    "node": frozenset({"list", "info", "ping", "kill"}),
    "topic": frozenset({"list", "info", "type", "find", "echo", "hz", "bw", "delay", "pub"}),
    "param": frozenset({"list", "get", "set", "delete", "dump", "load"}),
    "msg": frozenset({"show", "list", "md5"}),
    "srv": frozenset({"show", "list"}),
    "service": frozenset({"list", "type", "info", "uri", "find", "call"}),
    "action": frozenset({"list", "info", "send-goal", "cancel"}),
    "bag": frozenset({"info", "play", "record", "convert", "echo", "filter", "reindex"}),
    "cheatsheet": None,
}


def missing_rostool_verbs(reference: Reference, root: click.Command | None = None) -> list[str]:
    """Problems with the shown rostool forms, resolved against the live click tree.

    Each word after `rostool` must name a subcommand for as long as the current command is a group;
    once a leaf command is reached the remaining words are its arguments and flags.
    """
    if root is None:
        from rostool.cli import root as live_root

        root = live_root
    ctx = click.Context(root, info_name="rostool")
    problems = []
    for entry in reference.iter_entries():
        if entry.rostool is None:
            continue
        words = entry.rostool.split()
        command, path = root, ["rostool"]
        for word in words[1:]:
            if not isinstance(command, click.Group):
                break
            sub = command.get_command(ctx, word)
            if sub is None:
                problems.append(f"{entry.ros1}: '{' '.join(path)}' has no subcommand '{word}'")
                break
            command, path = sub, [*path, word]
    return problems


def unknown_rostool_flags(reference: Reference, root: click.Command | None = None) -> list[str]:
    """Flags in shown rostool forms that the resolved leaf command does not accept."""
    if root is None:
        from rostool.cli import root as live_root

        root = live_root
    ctx = click.Context(root, info_name="rostool")
    problems = []
    for entry in reference.iter_entries():
        if entry.rostool is None:
            continue
        command: click.Command | None = root
        words = entry.rostool.split()[1:]
        while words and isinstance(command, click.Group):
            command = command.get_command(ctx, words[0])
            words = words[1:]
        if command is None or isinstance(command, click.Group):
            continue
        accepted = {opt for param in command.params for opt in (*param.opts, *param.secondary_opts)}
        for word in words:
            if word.startswith("-") and word not in accepted:
                problems.append(f"{entry.ros1}: '{entry.rostool}' uses {word}, which {command.name} lacks")
    return problems


def unplanned_rostool_verbs(reference: Reference) -> list[str]:
    """rostool forms (shown or still hidden) that name a verb outside the planned tree."""
    problems = []
    for entry in reference.iter_entries():
        if entry.planned_rostool is None:
            continue
        words = entry.planned_rostool.split()
        group = words[1]
        if group not in PLANNED_TREE:
            problems.append(f"{entry.ros1}: no planned rostool group '{group}'")
            continue
        subcommands = PLANNED_TREE[group]
        if subcommands is not None and (len(words) < 3 or words[2] not in subcommands):
            problems.append(f"{entry.ros1}: no planned verb 'rostool {' '.join(words[1:3])}'")
    return problems
