"""The parameter tree of the embedded master, and which subscribers a change must reach.

Parameters form a tree of dicts: setting a dict at a key replaces that whole namespace, getting a
namespace returns its dict. Keys given here are already resolved (global). Not thread-safe: the master
holds its lock around every call.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rostool.graph.ros1.master_names import SEP, canonicalize, join

Subscriber = tuple[str, str]  # (caller_id, caller_api)
ParamUpdate = tuple[list[Subscriber], str, Any]  # (who, key sent in paramUpdate, value sent)


def _parts(key: str) -> list[str]:
    return [part for part in key.split(SEP) if part]


def copy_tree(value: Any) -> Any:
    """Copy the dict structure so a reader never sees a namespace change while it marshals it.

    Leaves are never mutated in place by the master, so they are shared.
    """
    if isinstance(value, dict):
        return {k: copy_tree(v) for k, v in value.items()}
    return value


class ParamTree:
    def __init__(self) -> None:
        self._root: dict[str, Any] = {}

    def get(self, key: str) -> Any:
        """The value (a copy) at `key`; raises KeyError when it is not set."""
        value: Any = self._root
        for part in _parts(key):
            if not isinstance(value, dict):
                raise KeyError(key)
            value = value[part]
        return copy_tree(value)

    def has(self, key: str) -> bool:
        value: Any = self._root
        for part in _parts(key):
            if not isinstance(value, dict) or part not in value:
                return False
            value = value[part]
        return True

    def set(self, key: str, value: Any) -> None:
        """Store `value` at `key`, turning any non-dict on the way into a namespace."""
        parts = _parts(key)
        if not parts:
            if not isinstance(value, dict):
                raise TypeError("cannot set root of parameter tree to non-dictionary")
            self._root = value
            return
        node = self._root
        for part in parts[:-1]:
            child = node.get(part)
            if not isinstance(child, dict):
                child = node[part] = {}
            node = child
        node[parts[-1]] = value

    def delete(self, key: str) -> None:
        """Remove `key` and everything under it; raises KeyError when it is not set."""
        parts = _parts(key)
        if not parts:
            raise KeyError("cannot delete root of parameter tree")
        node: Any = self._root
        for part in parts[:-1]:
            if not isinstance(node, dict) or part not in node:
                raise KeyError(key)
            node = node[part]
        if not isinstance(node, dict) or parts[-1] not in node:
            raise KeyError(key)
        del node[parts[-1]]

    def names(self) -> list[str]:
        """Every leaf parameter name (namespaces themselves are not listed)."""
        names: list[str] = []
        _collect_names(names, SEP, self._root)
        return names

    def search(self, namespace: str, key: str) -> str | None:
        """rosmaster's upward search: the first namespace from `namespace` up to / whose first
        component of `key` is set; returns the full key in that namespace (which need not exist)."""
        if not key or key.startswith("~"):
            raise ValueError("invalid key")
        if not namespace.startswith(SEP):
            raise ValueError("namespace must be global")
        if key.startswith(SEP):
            return key if self.has(key) else None
        first = _parts(key)[0]
        if self.has(join(namespace, first)):
            return join(namespace, key)
        levels = _parts(namespace)
        for up in range(1, len(levels) + 1):
            base = levels[:-up]
            if self.has(SEP + SEP.join([*base, first])):
                return SEP + SEP.join([*base, key])
        return None


def _collect_names(names: list[str], prefix: str, node: dict[str, Any]) -> None:
    for name, value in node.items():
        if isinstance(value, dict):
            _collect_names(names, join(prefix, name), value)
        else:
            names.append(join(prefix, name))


def _descendant_keys(key: str, value: dict[str, Any], out: list[str]) -> list[str]:
    for name, child in value.items():
        child_key = join(key, name) + SEP
        out.append(child_key)
        if isinstance(child, dict):
            _descendant_keys(child_key, child, out)
    return out


def param_updates(
    subscriptions: Mapping[str, Sequence[Subscriber]], key: str, value: Any, setter: str | None = None
) -> list[ParamUpdate]:
    """The paramUpdate calls a change of `key` to `value` causes (a deletion is the value {}).

    As rosmaster: keys sent end with a slash; a subscriber at or above the changed key gets the new
    value under the changed key (except the node that set it); a subscriber inside a replaced
    namespace gets its own key with its new value, or {} when that key is gone.
    """
    if not subscriptions:
        return []
    if key != SEP:
        key = canonicalize(key) + SEP
    changed = _descendant_keys(key, value, []) if isinstance(value, dict) else None
    updates: list[ParamUpdate] = []
    for sub_key, subscribers in subscriptions.items():
        ns_key = sub_key if sub_key.endswith(SEP) else sub_key + SEP
        if key.startswith(ns_key):
            targets = [s for s in subscribers if setter is None or s[0] != setter]
            updates.append((targets, key, value))
        elif ns_key.startswith(key) and (changed is None or sub_key not in changed):
            # rosmaster only reports this when a dict replaced the namespace; a plain value
            # replacing it removes the subscribed key just the same.
            updates.append((list(subscribers), sub_key, {}))
    for changed_key in changed or ():
        if changed_key in subscriptions:
            sub_value: Any = value
            for part in _parts(changed_key[len(key) :]):
                sub_value = sub_value[part]
            updates.append((list(subscriptions[changed_key]), changed_key, sub_value))
    return [update for update in updates if update[0]]
