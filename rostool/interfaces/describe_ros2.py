"""ROS 2 interfaces as `ros2 interface show` / `list` print them, with no network and no ROS install.

Types come from rosbags' store for ROS_DISTRO, rostool's built-in service and action definitions, and
.msg/.srv/.action files in the interface sources (--interfaces, ROSTOOL_INTERFACES, ROS_PACKAGE_PATH,
AMENT_PREFIX_PATH, the workspace around the current folder), through the ROS 2 types (ros2_types.py).

`ros2 interface show` prints the interface files as written. rosbags' store keeps no comments, blank lines
or field defaults, so the text here is rebuilt from the parsed definition: what `ros2 interface show
--no-comments` prints, except defaults of built-in types. Defaults of types from source files are shown.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from rosbags.interfaces import Nodetype

from rostool.errors import RostoolError
from rostool.interfaces.names import to_store_name

if TYPE_CHECKING:
    from rostool.interfaces.ros2_types import Ros2Types

KINDS = ("msg", "srv", "action")
_EMPTY_MEMBER = "structure_needs_at_least_one_member"  # rosbags' stand-in member of an empty message
_MAX_DEPTH = 32


def ros2_selected(explicit: int | None, type_name: str = "", env: Mapping[str, str] = os.environ) -> bool:
    """Whether the interface verbs answer for ROS 2: --ros1/--ros2, else ROS_VERSION, else a ROS 2 name
    (`pkg/msg/T`). Never probes for a master: these verbs need no graph, and without a ROS 2 hint the ROS 1
    answer stays the default."""
    if explicit in (1, 2):
        return explicit == 2
    env_version = env.get("ROS_VERSION", "").strip()
    if env_version in ("1", "2"):
        return env_version == "2"
    return kind_of(type_name) is not None


def kind_of(type_name: str) -> str | None:
    """`msg`, `srv` or `action` for a ROS 2 name `pkg/<kind>/T`, else None."""
    parts = type_name.strip().strip("/").split("/")
    return parts[1] if len(parts) == 3 and parts[1] in KINDS else None


def _short_name(store_name: str, package: str) -> str:
    """A nested type as .msg files write it: bare in its own package, else `pkg/Type`."""
    pkg, _kind, name = store_name.split("/")
    return name if pkg == package else f"{pkg}/{name}"


def _type_text(desc: Any, package: str) -> tuple[str, str | None]:
    """(field type as a .msg file writes it, nested message type to expand or None)."""
    kind, args = desc
    if kind == Nodetype.BASE:
        name, bound = args
        return (f"{name}<={bound}" if bound else name), None
    if kind == Nodetype.NAME:
        return _short_name(str(args), package), str(args)
    element, length = args
    inner, nested = _type_text(element, package)
    size = str(length) if kind == Nodetype.ARRAY else f"<={length}" if length else ""
    return f"{inner}[{size}]", nested


def _literal(value: Any) -> str:
    """A constant or default value as a .msg file writes it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_literal(v) for v in value) + "]"
    return str(value)


def describe_ros2(types: Ros2Types, store_name: str, level: int = 0) -> list[str]:
    """Constants, then fields (with source-file defaults), each nested type expanded one tab deeper."""
    if level > _MAX_DEPTH:
        raise RostoolError(f"{store_name} nests itself deeper than {_MAX_DEPTH} levels")
    consts, fields = types.store.fielddefs[store_name]
    package = store_name.split("/")[0]
    indent = "\t" * level
    defaults = types.sources.defaults.get(store_name, {})
    lines = [f"{indent}{ctype} {name}={_literal(value)}" for name, ctype, value in consts]
    for name, desc in fields:
        if name == _EMPTY_MEMBER:
            continue
        text, nested = _type_text(desc, package)
        default = f" {_literal(defaults[name])}" if name in defaults else ""
        lines.append(f"{indent}{text} {name}{default}")
        if nested is not None:
            lines.extend(describe_ros2(types, nested, level + 1))
    return lines


class Ros2Interfaces:
    """The ROS 2 types of one distro and set of interface sources, for show, list and hash."""

    def __init__(self, interface_paths: Sequence[str] = (), env: Mapping[str, str] = os.environ) -> None:
        from rostool.interfaces.ros2_types import Ros2Types, distro_from_env

        self.types = Ros2Types(distro_from_env(env), interface_paths)

    # show
    def show_lines(self, type_name: str, default_kind: str = "msg") -> list[str]:
        """What `ros2 interface show` prints for any kind of type (the name's `/srv/` or `/action/` part
        decides, else `default_kind`)."""
        kind = kind_of(type_name) or default_kind
        if kind == "srv":
            return self.service_lines(type_name)
        if kind == "action":
            return self.action_lines(type_name)
        return describe_ros2(self.types, self.message(type_name))

    def message(self, type_name: str) -> str:
        """The store name of a message type, loaded from source files when needed; an error if unknown."""
        return self.types.store_name(to_store_name(type_name.strip().strip("/")))

    def service_lines(self, type_name: str) -> list[str]:
        from rostool.interfaces.ros2_srv import register_service

        request, response = register_service(self.types, type_name)
        return [*describe_ros2(self.types, request), "---", *describe_ros2(self.types, response)]

    def action_lines(self, type_name: str) -> list[str]:
        from rostool.interfaces.ros2_action import register_action

        found = register_action(self.types, type_name)
        lines: list[str] = []
        for part in ("Goal", "Result", "Feedback"):
            if part != "Goal":
                lines.append("---")
            lines.extend(describe_ros2(self.types, found.part(part)))
        return lines

    def raw_text(self, type_name: str, kind: str) -> str | None:
        """The definition as written (comments included): rostool's built-in text or the source file; None
        for types only rosbags' store has (it keeps no text)."""
        from rostool.interfaces.ros2_action import ACTION_DEFINITIONS, action_store_name
        from rostool.interfaces.ros2_srv import SRV_DEFINITIONS

        store_name = action_store_name(type_name) if kind == "action" else to_store_name(type_name, kind)
        built_in = {**SRV_DEFINITIONS, **ACTION_DEFINITIONS}.get(store_name)
        if built_in is not None:
            return built_in
        path = self.types.sources.file_for(store_name)
        return path.read_text(encoding="utf-8") if path is not None else None

    # hash
    def type_hash(self, type_name: str) -> str:
        """The RIHS01 type hash (REP 2016) of a message type: what ROS 2 compares instead of an md5sum."""
        store_name = self.message(type_name)
        try:
            return str(self.types.store.hash_rihs01(store_name))
        except Exception as err:  # rosbags raises several kinds for definitions it cannot hash
            raise RostoolError(f"cannot compute the RIHS01 hash of {store_name}: {err}") from err

    # list
    def names(self, kind: str) -> list[str]:
        """Every type of `kind` (msg, srv, action) known: the store, rostool's built-ins, source files."""
        from rostool.interfaces.ros2_action import ACTION_DEFINITIONS
        from rostool.interfaces.ros2_srv import SRV_DEFINITIONS

        built_in = {
            "msg": [n for n in self.types.store.fielddefs if "/msg/" in n],
            "srv": list(SRV_DEFINITIONS),
            "action": list(ACTION_DEFINITIONS),
        }[kind]
        sources = self.types.sources.catalog.source_names(kind)
        return sorted({*built_in, *(to_store_name(n, kind) for n in sources)})

    def matches(self, bare_name: str, kind: str) -> list[str]:
        """Every type of `kind` called `bare_name` (as rosmsg does for a name without a package)."""
        return [n for n in self.names(kind) if n.endswith(f"/{bare_name}")]


def list_sections(catalog: Ros2Interfaces, kinds: Sequence[str]) -> list[str]:
    """`ros2 interface list` text: a `Messages:`/`Services:`/`Actions:` title, then names 4 spaces in."""
    titles = {"msg": "Messages:", "srv": "Services:", "action": "Actions:"}
    lines: list[str] = []
    for kind in kinds:
        lines.append(titles[kind])
        lines.extend(f"    {name}" for name in catalog.names(kind))
    return lines


def show_text(type_name: str, kind: str, interface_paths: Sequence[str] = (), raw: bool = False) -> str:
    """The text `rostool --ros2 msg|srv|action show` prints. A name without a package shows every type of
    `kind` so called, each under a `[pkg/kind/Type]:` title; `raw` prints the definition as written when
    rostool has its text."""
    catalog = Ros2Interfaces(interface_paths)
    name = type_name.strip().strip("/")
    if "/" in name:
        return _block(catalog, name, kind, raw)
    found = catalog.matches(name, kind)
    if not found:
        what = {"msg": "message", "srv": "service", "action": "action"}[kind]
        raise catalog.types.unknown(what, name)
    return "\n".join(f"[{full}]:\n{_block(catalog, full, kind, raw)}" for full in found)


def _block(catalog: Ros2Interfaces, type_name: str, kind: str, raw: bool) -> str:
    real_kind = kind_of(type_name) or kind
    text = catalog.raw_text(type_name, real_kind) if raw and real_kind != "msg" else None
    if text is not None:
        return text if text.endswith("\n") or not text else text + "\n"
    lines = catalog.show_lines(type_name, kind)
    return "".join(f"{line}\n" for line in lines)


# --- show with comments (the definition files as written) -------------------------------------------------

_PRIMITIVES = frozenset(
    {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32", "uint32"}
    | {"int64", "uint64", "string", "wstring"}
)
_TRAILING_COMMENT = re.compile(r"\s#")


def commented_text(
    type_name: str, kind: str, interface_paths: Sequence[str] = (), all_comments: bool = False
) -> str | None:
    """What `ros2 interface show` prints from the definition file: its comments and blank lines, nested
    types expanded one tab deeper (their comments too with `all_comments`). None when rostool has no text
    for the type (rosbags' store keeps none): the caller prints the rebuilt definition instead."""
    catalog = Ros2Interfaces(interface_paths)
    name = type_name.strip().strip("/")
    if "/" not in name:
        return None
    text = catalog.raw_text(name, kind_of(name) or kind)
    if text is None:
        return None
    lines = _commented(catalog, text, name.split("/")[0], 0, all_comments)
    return "".join(f"{line}\n" for line in lines)


def _commented(catalog: Ros2Interfaces, text: str, package: str, level: int, all_comments: bool) -> list[str]:
    if level > _MAX_DEPTH:
        raise RostoolError(f"a type of {package} nests itself deeper than {_MAX_DEPTH} levels")
    indent, comments = "\t" * level, level == 0 or all_comments
    lines: list[str] = []
    for raw in text.splitlines():
        line = raw.strip()
        if line == "---" and level == 0:
            lines.append(line)
        elif not line or line.startswith("#"):
            if comments:
                lines.append(indent + line if line else "")
        else:
            code = _TRAILING_COMMENT.split(line, maxsplit=1)[0].rstrip()
            lines.append(indent + (line if comments else code))
            nested = _nested_type(code, package)
            if nested is not None:
                lines.extend(_nested_lines(catalog, nested, level + 1, all_comments))
    return lines


def _nested_type(code: str, package: str) -> str | None:
    """The message type a field line names (`pkg/msg/T`), or None for primitives and constants."""
    words = code.split()
    if len(words) < 2 or "=" in words[1] or (len(words) > 2 and words[2].startswith("=")):
        return None
    base = re.sub(r"\[[^\]]*\]$", "", words[0]).split("<=")[0]
    if base in _PRIMITIVES:
        return None
    parts = base.split("/")
    if len(parts) == 3:
        return base
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else f"{package}/msg/{base}"


def _nested_lines(catalog: Ros2Interfaces, store_name: str, level: int, all_comments: bool) -> list[str]:
    text = catalog.raw_text(store_name, "msg")
    if text is None:
        return describe_ros2(catalog.types, catalog.message(store_name), level)
    return _commented(catalog, text, store_name.split("/")[0], level, all_comments)
