"""ROS 2 interface definitions: .msg/.srv/.action text -> rosbags types named as rosidl names them.

- `pkg/msg/T.msg` -> `pkg/msg/T`;
- `pkg/srv/T.srv` -> `pkg/srv/T_Request` and `pkg/srv/T_Response`;
- `pkg/action/T.action` -> `pkg/action/T_Goal`, `_Result`, `_Feedback` and the types rosidl_parser's
  `Action` derives from them: `T_SendGoal_Request` (goal_id, goal), `T_SendGoal_Response` (accepted, stamp),
  `T_GetResult_Request` (goal_id), `T_GetResult_Response` (status, result) and `T_FeedbackMessage`
  (goal_id, feedback), goal_id being a unique_identifier_msgs/msg/UUID.

rosbags' parser reads past field default values (`float64 speed 0.5`); they are read here, so messages
built from partial values get them as rosidl's generated classes do.

Source files are found like the ROS 1 side finds them (rostool.interfaces.sources: --interfaces,
ROSTOOL_INTERFACES, ROS_PACKAGE_PATH, the workspace around the current folder), plus the `share/` folder
of every AMENT_PREFIX_PATH entry, where installed ROS 2 packages keep their interface files.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import get_types_from_msg

import rostool.interfaces.rosbags_fix  # noqa: F401 - must run before types are registered
from rostool.errors import RostoolError
from rostool.interfaces.msgspec import InterfaceError
from rostool.interfaces.sources import Interfaces, SourceRoot, default_roots

Typesdict = dict[str, Any]  # rosbags' {store name: (constants, fields)}

UUID_TYPE = "unique_identifier_msgs/msg/UUID"
TIME_TYPE = "builtin_interfaces/msg/Time"
ACTION_PARTS = ("Goal", "Result", "Feedback")
# Longest first: `X_SendGoal_Request` must not be taken for an action named `X_SendGoal`.
_ACTION_SUFFIXES = (
    "_SendGoal_Request", "_SendGoal_Response", "_GetResult_Request", "_GetResult_Response",
    "_FeedbackMessage", "_Goal", "_Result", "_Feedback",
)  # fmt: skip
_SERVICE_SUFFIXES = ("_Request", "_Response")


def split_sections(text: str) -> list[str]:
    """The sections of .srv/.action text: rosidl splits at lines that are `---` (trailing spaces allowed)."""
    sections: list[list[str]] = [[]]
    for line in text.split("\n"):
        if line.rstrip() == "---":
            sections.append([])
        else:
            sections[-1].append(line)
    return ["\n".join(lines) + "\n" for lines in sections]


def parse_message(text: str, store_name: str, origin: str) -> Typesdict:
    """One message definition filed under `store_name` (`pkg/<kind>/Name`); nested names resolve in `pkg/msg`
    as rosidl resolves them."""
    pkg, _kind, name = store_name.split("/")
    as_msg = f"{pkg}/msg/{name}"  # rosbags' parser files every type under pkg/msg
    try:
        parsed = get_types_from_msg(text, as_msg)
    except Exception as err:  # rosbags raises several kinds for text it cannot take
        raise InterfaceError(f"{origin}: cannot use the definition of {store_name}: {err}") from err
    found = parsed.pop(as_msg)
    return {**parsed, store_name: found}


def _strip_comment(line: str) -> str:
    """The line up to a `#` outside quotes (a string default may hold one)."""
    quote = ""
    for index, char in enumerate(line):
        if quote:
            quote = "" if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char == "#":
            return line[:index]
    return line


def default_values(text: str, origin: str = "") -> dict[str, Any]:
    """The fields of one message section that have a default (`TYPE NAME VALUE`), with their values."""
    from yaml import YAMLError, safe_load

    found: dict[str, Any] = {}
    for line in text.split("\n"):
        parts = _strip_comment(line).strip().split(None, 2)
        if len(parts) < 3 or "=" in parts[1] or parts[2].startswith("="):  # no default, or a constant
            continue
        field_type, name, raw = parts[0], parts[1], parts[2].strip()
        if field_type.startswith(("string", "wstring")) and "[" not in field_type:
            quoted = len(raw) >= 2 and raw[0] == raw[-1] and raw[0] in "'\""
            found[name] = raw[1:-1] if quoted else raw
            continue
        try:
            value = safe_load(raw)
        except YAMLError as err:
            raise InterfaceError(f"{origin}: the default value of {name} is not readable: {raw!r}") from err
        found[name] = bool(value) if field_type == "bool" else value
    return found


def parts_of(text: str, store_names: Sequence[str], origin: str, layout: str) -> Typesdict:
    """Each `---` section of .srv/.action text parsed as its own message, named in order."""
    sections = split_sections(text)
    if len(sections) != len(store_names):
        raise InterfaceError(f"{origin}: {layout}; this one has {len(sections)} sections")
    typs: Typesdict = {}
    for store_name, body in zip(store_names, sections, strict=True):
        typs.update(parse_message(body, store_name, origin))
    return typs


def service_types(srv_type: str, text: str, origin: str) -> Typesdict:
    """`pkg/srv/T_Request` and `_Response` from .srv text."""
    layout = "a .srv file has a request and a response separated by a --- line"
    return parts_of(text, [srv_type + suffix for suffix in _SERVICE_SUFFIXES], origin, layout)


def action_types(action_type: str, text: str, origin: str) -> Typesdict:
    """An action's goal, result and feedback from .action text, and the five types rosidl derives."""
    layout = "an .action file has goal, result and feedback separated by --- lines"
    typs = parts_of(text, [f"{action_type}_{part}" for part in ACTION_PARTS], origin, layout)

    def member(name: str, type_name: str) -> tuple[str, Any]:
        return name, (Nodetype.NAME, type_name)

    goal_id = member("goal_id", UUID_TYPE)
    typs[f"{action_type}_SendGoal_Request"] = ([], [goal_id, member("goal", f"{action_type}_Goal")])
    typs[f"{action_type}_SendGoal_Response"] = (
        [], [("accepted", (Nodetype.BASE, ("bool", 0))), member("stamp", TIME_TYPE)]
    )  # fmt: skip
    typs[f"{action_type}_GetResult_Request"] = ([], [goal_id])
    typs[f"{action_type}_GetResult_Response"] = (
        [], [("status", (Nodetype.BASE, ("int8", 0))), member("result", f"{action_type}_Result")]
    )  # fmt: skip
    typs[f"{action_type}_FeedbackMessage"] = ([], [goal_id, member("feedback", f"{action_type}_Feedback")])
    return typs


def _source_file(store_name: str) -> tuple[str, str, str] | None:
    """(package, kind, file stem) of the source file that defines `store_name` (a service's or action's own
    name gives its file too), None for names of no source file."""
    parts = store_name.split("/")
    if len(parts) != 3 or not all(parts):
        return None
    pkg, kind, name = parts
    if kind == "msg":
        return pkg, "msg", name
    suffixes = {"srv": _SERVICE_SUFFIXES, "action": _ACTION_SUFFIXES}.get(kind, ())
    for suffix in suffixes:
        if name.endswith(suffix) and len(name) > len(suffix):
            return pkg, kind, name.removesuffix(suffix)
    return (pkg, kind, name) if suffixes else None


def _nested_names(typs: Typesdict) -> list[str]:
    found: list[str] = []

    def visit(desc: Any) -> None:
        kind, args = desc
        if kind == Nodetype.NAME:
            found.append(args)
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            visit(args[0])

    for _consts, fields in typs.values():
        for _name, desc in fields:
            visit(desc)
    return found


def ament_roots(env: Mapping[str, str] = os.environ) -> list[SourceRoot]:
    """`share/` of every AMENT_PREFIX_PATH entry: installed packages keep their interface files there."""
    roots = []
    for entry in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        share = Path(entry.strip()).expanduser() / "share"
        if entry.strip() and share.is_dir():
            roots.append(SourceRoot("AMENT_PREFIX_PATH", share))
    return roots


class SourceDefinitions:
    """Types from .msg/.srv/.action files, loaded (with everything they nest) the first time one is asked."""

    def __init__(self, paths: Sequence[str | Path] = ()) -> None:
        self.paths = tuple(str(p) for p in paths)
        self.defaults: dict[str, dict[str, Any]] = {}  # store name -> {field: default value}
        self._catalog: Interfaces | None = None
        self._lock = threading.RLock()

    @property
    def catalog(self) -> Interfaces:
        with self._lock:
            if self._catalog is None:  # made on first need: finding the sources walks folders
                self._catalog = Interfaces(roots=[*default_roots(self.paths), *ament_roots()])
            return self._catalog

    def searched(self) -> str:
        roots = self.catalog.roots
        if not roots:
            return "no --interfaces, ROS_PACKAGE_PATH or AMENT_PREFIX_PATH; no workspace around this folder"
        return "; ".join(f"{root.label} {root.path}" for root in roots)

    def file_for(self, store_name: str) -> Path | None:
        where = _source_file(store_name)
        return self.catalog.find_file(*where) if where is not None else None

    def missing_detail(self, store_name: str) -> str:
        """Why no file defines `store_name`: no such package, or the package lacks the file."""
        where = _source_file(store_name)
        if where is None:
            return f"{store_name!r} is not a pkg/msg|srv|action/Name type"
        package, kind, stem = where
        dirs = self.catalog.packages().get(package, [])
        if not dirs:
            return f"no package {package} in the sources"
        return f"package {package} (at {', '.join(str(d) for d in dirs)}) has no {kind}/{stem}.{kind}"

    def load(self, store_name: str, known: Callable[[str], bool]) -> Typesdict | None:
        """The types of the file that defines `store_name` and of every type they nest that `known` does not
        know; None when no source file defines `store_name`. A nested type found nowhere is an error."""
        with self._lock:
            pending: Typesdict = {}
            if not self._add_file(store_name, pending):
                return None
            queue = _nested_names(pending)
            while queue:
                nested = queue.pop()
                if nested in pending or known(nested):
                    continue
                if not self._add_file(nested, pending):
                    users = sorted(n for n, typ in pending.items() if nested in _nested_names({n: typ}))
                    raise InterfaceError(
                        f"unknown message type {nested} (used by {', '.join(users)}): "
                        f"{self.missing_detail(nested)}. Looked in the ROS 2 type store and {self.searched()}"
                    )
                queue.extend(_nested_names(pending))
            return pending

    def _add_file(self, store_name: str, pending: Typesdict) -> bool:
        where = _source_file(store_name)
        path = self.file_for(store_name)
        if where is None or path is None:
            return False
        package, kind, stem = where
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise InterfaceError(f"cannot read {path}: {err}") from err
        full = f"{package}/{kind}/{stem}"
        if kind == "msg":
            pending.update(parse_message(text, full, str(path)))
            names = [full]
        elif kind == "srv":
            pending.update(service_types(full, text, str(path)))
            names = [full + suffix for suffix in _SERVICE_SUFFIXES]
        else:
            pending.update(action_types(full, text, str(path)))
            names = [f"{full}_{part}" for part in ACTION_PARTS]
        for name, section in zip(names, split_sections(text) if kind != "msg" else [text], strict=True):
            defaults = default_values(section, str(path))
            if defaults:
                self.defaults[name] = defaults
        return store_name in pending


def unknown_type_error(
    what: str, name: str, store_name: str, searched: str, sources: SourceDefinitions, hint: str
) -> RostoolError:
    """One line naming everything searched for a type (`name` as the user wrote it)."""
    return RostoolError(
        f"unknown {what} type {name!r}: searched {searched} and the interface sources "
        f"({sources.searched()}): {sources.missing_detail(store_name)}. {hint}"
    )
