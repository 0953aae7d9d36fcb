"""ROS 1 interface definitions from source trees (.msg/.srv/.action), parsed and hashed as genmsg does.

Where a type comes from, first match wins:
  1. `--interfaces PATH` (repeatable): a workspace, a package, a folder of packages, or one file;
  2. ROS_PACKAGE_PATH;
  3. the catkin/colcon workspace around the current directory (`src/<pkg>/{msg,srv,action}/`);
  4. built-in types: rosbags' Noetic messages and the standard services of `srv.py`.
Types a peer announces on the wire (or a bag stores) are resolved before any of these, by TypeRegistry.

md5sums come from the source text with genmsg's rules (comments and spacing dropped, constants first with
their written value, nested types replaced by their md5), so catkin-built peers accept what we send;
rosbags provides the message classes and the (de)serializers.
"""

from __future__ import annotations

import hashlib
import os
import re
import threading
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

if TYPE_CHECKING:
    from rosbags.interfaces.typing import Typesdict
    from rosbags.typesys.store import Typestore

import rostool.interfaces.rosbags_fix  # noqa: F401 - must run before types are registered
from rostool.errors import RostoolError
from rostool.interfaces.names import to_ros1_name, to_store_name
from rostool.interfaces.ros1 import Ros1Type, builtin_store

PRIMITIVE_TYPES = frozenset(
    {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
     "float32", "float64", "string", "bool", "char", "byte"}
)  # fmt: skip
BUILTIN_TYPES = PRIMITIVE_TYPES | {"time", "duration"}
_BITS = {"int8": 8, "uint8": 8, "int16": 16, "uint16": 16, "int32": 32, "uint32": 32,
         "int64": 64, "uint64": 64, "byte": 8, "char": 8}  # fmt: skip
_RESOURCE = re.compile(r"[A-Za-z][\w/]*\Z", re.ASCII)
_BASE_NAME = re.compile(r"[A-Za-z]\w*\Z", re.ASCII)
_ARRAY = re.compile(r"(\[\d*\])*\Z")
_ROSBAGS_CONSTANT = re.compile(r"[A-Z](?:_?[A-Z0-9]+)*\Z")  # rosbags' grammar; others are skipped there
_SEPARATOR = "=" * 80
_IGNORE_MARKERS = ("CATKIN_IGNORE", "COLCON_IGNORE", "AMENT_IGNORE")
_CRAWL_DEPTH = 6
_CRAWL_LIMIT = 20_000  # folders visited per root
KINDS = ("msg", "srv", "action")
INTERFACES_ENV = "ROSTOOL_INTERFACES"


def interface_paths_from_env() -> tuple[str, ...]:
    """ROSTOOL_INTERFACES split as click splits it for --interfaces (at os.pathsep): verbs without the
    option (topic echo) find custom types there too."""
    value = os.environ.get(INTERFACES_ENV, "")
    return tuple(p for p in value.split(os.pathsep) if p.strip())


class InterfaceError(RostoolError):
    """A definition that cannot be used: malformed text (with file:line) or a type found nowhere."""


# --- parsing ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Field:
    type: str  # as genmsg resolves it: builtins as written, `Header` -> std_msgs/Header, `T` -> pkg/T
    name: str

    @property
    def base_type(self) -> str:
        return self.type.split("[", 1)[0]


@dataclass(frozen=True)
class Constant:
    type: str
    name: str
    value_text: str


@dataclass(frozen=True)
class MsgSpec:
    """One message definition: what genmsg's MsgSpec holds, plus where it came from."""

    name: str  # pkg/Type
    text: str
    constants: tuple[Constant, ...]
    fields: tuple[Field, ...]
    origin: str

    @property
    def package(self) -> str:
        return self.name.split("/", 1)[0]

    def depends(self) -> list[str]:
        """Nested message types in field order, each once."""
        found: list[str] = []
        for field in self.fields:
            base = field.base_type
            if base not in BUILTIN_TYPES and base not in found:
                found.append(base)
        return found

    def md5_text(self, md5_of: Callable[[str], str]) -> str:
        lines = [f"{c.type} {c.name}={c.value_text}" for c in self.constants]
        for field in self.fields:
            base = field.base_type
            lines.append(f"{field.type if base in BUILTIN_TYPES else md5_of(base)} {field.name}")
        return "\n".join(lines).strip()

    def rosbags_text(self) -> str:
        """The definition with every type spelled in full, for rosbags' parser."""
        lines = [
            f"{c.type} {c.name}={c.value_text}" for c in self.constants if _ROSBAGS_CONSTANT.match(c.name)
        ]
        lines.extend(f"{f.type} {f.name}" for f in self.fields)
        return "\n".join(lines) + "\n"


NumberedLines = Sequence[tuple[int, str]]  # (1-based line number in the file, 0 when generated; text)


def numbered(text: str, first: int = 1) -> list[tuple[int, str]]:
    return [(first + index, line) for index, line in enumerate(text.split("\n"))]


def parse_msg(text: str, name: str, origin: str, lines: NumberedLines | None = None) -> MsgSpec:
    """Parse .msg text with genmsg's rules; problems raise InterfaceError naming `origin:line`."""
    package = name.split("/", 1)[0]
    constants: list[Constant] = []
    fields: list[Field] = []
    for number, line in lines if lines is not None else numbered(text):
        clean = line.split("#", 1)[0].strip()
        if not clean:
            continue
        try:
            if "=" in clean:
                constants.append(_constant(line, clean))
            else:
                fields.append(_field(clean, package))
                if any(f.name == fields[-1].name for f in fields[:-1]):
                    raise ValueError(f"field {fields[-1].name!r} is declared twice in {name}")
        except ValueError as err:
            raise InterfaceError(f"{_where(origin, number)}: {err}") from None
    return MsgSpec(name, text, tuple(constants), tuple(fields), origin)


def _where(origin: str, number: int) -> str:
    return f"{origin}:{number}" if number else origin


def _field(clean: str, package: str) -> Field:
    parts = clean.split()
    if len(parts) != 2:
        raise ValueError(f"expected `TYPE NAME` (or `TYPE NAME=VALUE` for a constant), got {clean!r}")
    field_type, name = parts
    if not _BASE_NAME.match(name):
        raise ValueError(f"{name!r} is not a legal field name (a letter, then letters, digits or _)")
    base = field_type.split("[", 1)[0]
    if not _RESOURCE.match(base) or base.count("/") > 1 or not _ARRAY.match(field_type[len(base) :]):
        raise ValueError(f"{field_type!r} is not a legal field type (like int32, pkg/Type or Type[3])")
    if "/" not in base:
        if base == "Header":
            field_type = "std_msgs/" + field_type
        elif base not in BUILTIN_TYPES:
            field_type = f"{package}/{field_type}"
    return Field(field_type, name)


def _constant(line: str, clean: str) -> Constant:
    parts = clean.split()
    const_type = parts[0]
    if const_type not in PRIMITIVE_TYPES:
        raise ValueError(f"{const_type!r} cannot be a constant type (only numbers, bool and string)")
    if const_type == "string":  # everything right of `=` is the value, `#` included
        name = line[line.find(" ") + 1 : line.find("=")].strip()
        value = line[line.find("=") + 1 :].strip()
    else:
        pieces = [p.strip() for p in " ".join(parts[1:]).split("=")]
        if len(pieces) != 2:
            raise ValueError(f"invalid constant declaration {clean!r}")
        name, value = pieces
        _check_constant_value(const_type, value)
    if not _BASE_NAME.match(name):
        raise ValueError(f"{name!r} is not a legal constant name")
    return Constant(const_type, name, value)


def _check_constant_value(const_type: str, value: str) -> None:
    if const_type in ("float32", "float64"):
        try:
            float(value)
        except ValueError:
            raise ValueError(f"constant value {value!r} is not a {const_type}") from None
    elif const_type == "bool":
        if value not in ("True", "False", "true", "false", "1", "0"):
            raise ValueError(f"constant value {value!r} is not a bool (True or False)")
    else:
        try:
            number = int(value)
        except ValueError:
            raise ValueError(f"constant value {value!r} is not an integer") from None
        bits = _BITS[const_type]
        low, high = (0, 2**bits - 1) if const_type[0] == "u" or const_type == "char" else (
            -(2 ** (bits - 1)), 2 ** (bits - 1) - 1)  # fmt: skip
        if not low <= number <= high:
            raise ValueError(f"constant value {number} does not fit a {const_type} ({low}..{high})")


# --- finding packages ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class SourceRoot:
    label: str  # "--interfaces", "ROS_PACKAGE_PATH", "workspace"
    path: Path


def package_name(directory: Path) -> str:
    """The <name> in package.xml, else the folder's name."""
    try:
        found = re.search(r"<name>\s*([^<\s]+)\s*</name>", (directory / "package.xml").read_text())
    except (OSError, UnicodeDecodeError):
        found = None
    return found.group(1) if found else directory.name


def _has_interfaces(directory: Path) -> bool:
    """A msg/, srv/ or action/ folder holding files of that kind (a bare /srv is not one)."""
    for kind in KINDS:
        folder = directory / kind
        try:
            if folder.is_dir() and next(folder.glob(f"*.{kind}"), None) is not None:
                return True
        except OSError:
            continue
    return False


def crawl(root: Path, depth: int = _CRAWL_DEPTH) -> Iterator[Path]:
    """Package folders under `root` (a folder with package.xml, or with msg/srv/action folders)."""
    seen: set[Path] = set()

    def walk(directory: Path, level: int) -> Iterator[Path]:
        try:
            real = directory.resolve()
        except OSError:
            return
        if real in seen or len(seen) >= _CRAWL_LIMIT:  # a bounded walk, even for ROS_PACKAGE_PATH=/usr
            return
        seen.add(real)
        if any((directory / marker).exists() for marker in _IGNORE_MARKERS):
            return
        if (directory / "package.xml").is_file() or (level > 0 and _has_interfaces(directory)):
            yield directory
            return
        if level >= depth:
            return
        try:
            children = sorted(p for p in directory.iterdir() if p.is_dir() and not p.name.startswith("."))
        except OSError:
            return
        for child in children:
            yield from walk(child, level + 1)

    if root.is_dir() and not (root / "package.xml").is_file() and _has_interfaces(root):
        yield root  # a bare folder holding msg/ srv/ action/: the folder is the package
        return
    yield from walk(root, 0)


def _is_package(directory: Path) -> bool:
    return (directory / "package.xml").is_file() or _has_interfaces(directory)


def _shallow_packages(src: Path) -> bool:
    """Does `src` look like a workspace's source space (src/<pkg>/ or src/<group>/<pkg>/)?"""
    try:
        for child in list(src.iterdir())[:200]:
            if not child.is_dir():
                continue
            if _is_package(child) or any(g.is_dir() and _is_package(g) for g in list(child.iterdir())[:200]):
                return True
    except OSError:
        return False
    return False


def workspace_roots(cwd: Path) -> list[SourceRoot]:
    """The workspace around `cwd`: the nearest ancestor with a src/ of packages, else our package."""
    package: Path | None = None
    for directory in (cwd, *cwd.parents):
        src = directory / "src"
        if src.is_dir() and _shallow_packages(src):
            return [SourceRoot("workspace", src)]
        if package is None and _is_package(directory):
            package = directory
    return [SourceRoot("workspace", package)] if package is not None else []


def default_roots(paths: Sequence[str | Path] = (), cwd: Path | None = None) -> list[SourceRoot]:
    roots = [SourceRoot("--interfaces", Path(p).expanduser()) for p in paths]
    for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
        if entry.strip():
            roots.append(SourceRoot("ROS_PACKAGE_PATH", Path(entry.strip()).expanduser()))
    roots.extend(workspace_roots(cwd or Path.cwd()))
    return roots


# --- the catalog --------------------------------------------------------------------------------------
ACTION_SUFFIXES = ("ActionGoal", "ActionResult", "ActionFeedback", "Action", "Goal", "Result", "Feedback")


class Interfaces:
    """Message, service and action types from the sources above; thread-safe, caches what it parses."""

    def __init__(self, paths: Sequence[str | Path] = (), roots: Sequence[SourceRoot] | None = None) -> None:
        self.roots = list(roots) if roots is not None else default_roots(paths)
        self._lock = threading.RLock()
        self._packages: dict[str, list[Path]] | None = None
        self._files: dict[tuple[str, str, str], Path] = {}  # single files given to --interfaces
        self._specs: dict[str, MsgSpec | None] = {}
        self._md5: dict[str, str] = {}
        self._hashing: set[str] = set()
        self._store: Typestore = get_typestore(Stores.EMPTY)
        self._types: dict[str, Ros1Type] = {}
        self.memo: dict[tuple[str, str], object] = {}  # services and actions built from these types

    # discovery
    def packages(self) -> dict[str, list[Path]]:
        with self._lock:
            if self._packages is None:
                self._packages = self._discover()
            return self._packages

    def _discover(self) -> dict[str, list[Path]]:
        packages: dict[str, list[Path]] = {}
        for root in self.roots:
            path = root.path
            if path.is_file():
                self._add_file(path)
                continue
            if (path / "src").is_dir() and not (path / "package.xml").is_file():
                path = path / "src"  # a workspace root
            for directory in crawl(path):
                dirs = packages.setdefault(package_name(directory), [])
                if directory not in dirs:
                    dirs.append(directory)
        return packages

    def _add_file(self, path: Path) -> None:
        kind = path.suffix.lstrip(".")
        if kind not in KINDS:
            return
        folder = path.parent.parent if path.parent.name in KINDS else path.parent
        self._files.setdefault((package_name(folder), kind, path.stem), path)

    def find_file(self, package: str, kind: str, name: str) -> Path | None:
        packages = self.packages()
        single = self._files.get((package, kind, name))
        if single is not None:
            return single
        for directory in packages.get(package, []):
            candidate = directory / kind / f"{name}.{kind}"
            if candidate.is_file():
                return candidate
        return None

    def source_names(self, kind: str) -> list[str]:
        """`pkg/Type` of every file of `kind` (msg, srv or action) in the sources."""
        packages = self.packages()  # also collects the single files
        names = {f"{pkg}/{stem}" for (pkg, k, stem) in self._files if k == kind}
        for package, dirs in packages.items():
            for directory in dirs:
                folder = directory / kind
                if folder.is_dir():
                    names.update(f"{package}/{p.stem}" for p in folder.glob(f"*.{kind}") if p.is_file())
        return sorted(names)

    def searched(self) -> str:
        """Where types were looked for, for error messages."""
        if not self.roots:
            where = (
                "no --interfaces paths, ROS_PACKAGE_PATH is not set and no workspace around this directory"
            )
        else:
            where = "; ".join(f"{r.label} {r.path}" for r in self.roots)
        return f"{where}; built-in ROS 1 types"

    def not_found(self, kind: str, name: str) -> InterfaceError:
        package, _, short = name.partition("/")
        dirs = self.packages().get(package, [])
        if dirs:
            detail = f"package {package} (at {', '.join(str(d) for d in dirs)}) has no {kind}/{short}.{kind}"
        else:
            detail = f"no package {package} found"
        what = {"msg": "message", "srv": "service", "action": "action"}[kind]
        return InterfaceError(
            f"unknown {what} type {name}: {detail}. Looked in: {self.searched()}. "
            "Point --interfaces (or ROS_PACKAGE_PATH) at the source tree that defines it"
        )

    # messages
    def spec(self, name: str) -> MsgSpec | None:
        """The source definition of message `pkg/Type`, or None when it must come from the built-in store."""
        name = to_ros1_name(to_store_name(name))
        with self._lock:
            if name not in self._specs:
                self._specs[name] = self._load_spec(name)
            return self._specs[name]

    def _load_spec(self, name: str) -> MsgSpec | None:
        package, _, short = name.partition("/")
        path = self.find_file(package, "msg", short)
        if path is not None:
            text = _read(path)
            return parse_msg(text, name, str(path))
        for suffix in ("Request", "Response"):  # the two halves of a .srv are messages too (as in genpy)
            base = short[: -len(suffix)]
            if short.endswith(suffix) and base and self.find_file(package, "srv", base) is not None:
                from rostool.interfaces.srv import load_service

                load_service(self, f"{package}/{base}")
                return self._specs.get(name)
        for suffix in ACTION_SUFFIXES:
            base = short[: -len(suffix)]
            if short.endswith(suffix) and base and self.find_file(package, "action", base) is not None:
                from rostool.interfaces.action import load_action_specs

                path = self.find_file(package, "action", base)
                assert path is not None
                specs = load_action_specs(_read(path), f"{package}/{base}", str(path))
                self._specs.update(specs)
                return specs[name]
        return None

    def add_specs(self, specs: dict[str, MsgSpec]) -> None:
        """Definitions parsed elsewhere (a .srv's request and response, an .action's messages)."""
        with self._lock:
            for name, spec in specs.items():
                if self._specs.get(name) is None:
                    self._specs[name] = spec

    def has_message(self, name: str) -> bool:
        return self.spec(name) is not None or to_store_name(name) in builtin_store().fielddefs

    def md5(self, name: str) -> str:
        name = to_ros1_name(to_store_name(name))
        with self._lock:
            cached = self._md5.get(name)
            if cached is not None:
                return cached
            spec = self.spec(name)
            if spec is None:
                store = builtin_store()
                if to_store_name(name) not in store.fielddefs:
                    raise self.not_found("msg", name)
                md5sum = store.generate_msgdef(to_store_name(name))[1]
            else:
                if name in self._hashing:
                    raise InterfaceError(f"{spec.origin}: {name} contains itself; ROS 1 types cannot nest so")
                self._hashing.add(name)
                try:
                    md5sum = hashlib.md5(spec.md5_text(self.md5).encode()).hexdigest()
                finally:
                    self._hashing.discard(name)
            self._md5[name] = md5sum
            return md5sum

    def message(self, name: str) -> Ros1Type:
        """The wire type of message `pkg/Type` (source definitions first, then the built-in store)."""
        name = to_ros1_name(to_store_name(name))
        with self._lock:
            known = self._types.get(name)
            if known is not None:
                return known
            if self.spec(name) is None:
                store = builtin_store()
                if to_store_name(name) not in store.fielddefs:
                    raise self.not_found("msg", name)
                definition, md5sum = store.generate_msgdef(to_store_name(name))
                found = Ros1Type(name, md5sum, definition, store)
            else:
                self._register(name)
                found = Ros1Type(name, self.md5(name), self.full_text(name), self._store)
            self._types[name] = found
            return found

    def full_text(self, name: str) -> str:
        """The `message_definition` genmsg would send: the text, then each nested type's text once."""
        parts = [self._own_text(name) + "\n"]
        for dep in self._all_depends(name):
            parts.append(f"{_SEPARATOR}\nMSG: {dep}\n{self._own_text(dep)}\n")
        return "".join(parts)[:-1]

    def _own_text(self, name: str) -> str:
        spec = self.spec(name)
        if spec is not None:
            return spec.text
        return builtin_store().gendefhash(to_store_name(name), {})[0]

    def _direct_depends(self, name: str) -> list[str]:
        spec = self.spec(name)
        if spec is not None:
            return spec.depends()
        found: list[str] = []
        for _field_name, desc in builtin_store().fielddefs[to_store_name(name)][1]:
            kind: int = desc[0]
            nested: object = desc[1]
            if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) and isinstance(nested, tuple):
                kind, nested = nested[0][0], nested[0][1]
            if kind == Nodetype.NAME and isinstance(nested, str) and not nested.startswith("builtin_"):
                ros1 = to_ros1_name(nested)
                if ros1 not in found:
                    found.append(ros1)
        return found

    def _all_depends(self, name: str) -> list[str]:
        ordered: list[str] = []

        def visit(current: str) -> None:
            for dep in self._direct_depends(current):
                if dep not in ordered:
                    ordered.append(dep)
                visit(dep)

        visit(name)
        return ordered

    def _register(self, name: str) -> None:
        """Put `name` and everything it contains into this catalog's store."""
        pending: Typesdict = {}
        for type_name in [name, *self._all_depends(name)]:
            store_name = to_store_name(type_name)
            if store_name in self._store.fielddefs or store_name in pending:
                continue
            spec = self.spec(type_name)
            if spec is None:
                store = builtin_store()
                if store_name not in store.fielddefs:
                    raise self.not_found("msg", type_name)
                pending[store_name] = store.fielddefs[store_name]
                continue
            try:
                pending.update(get_types_from_msg(spec.rosbags_text(), store_name))
            except Exception as err:  # rosbags raises several kinds for text it cannot take
                raise InterfaceError(
                    f"{spec.origin}: cannot use the definition of {type_name}: {err}"
                ) from err
        for time_type in ("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"):
            if time_type not in self._store.fielddefs:
                pending[time_type] = builtin_store().fielddefs[time_type]
        if pending:
            self._store.register(pending)

    def show_lines(self, name: str, indent: str = "") -> list[str]:
        """The type as `rosmsg show` prints it: constants as written, fields, nested types indented."""
        spec = self.spec(name)
        if spec is None:
            from rostool.interfaces.describe import describe

            store = builtin_store()
            if to_store_name(name) not in store.fielddefs:
                raise self.not_found("msg", to_ros1_name(to_store_name(name)))
            return describe(store, to_store_name(name), indent)
        if len(indent) > 64:
            raise InterfaceError(f"{spec.origin}: {spec.name} contains itself; ROS 1 types cannot nest so")
        lines = [f"{indent}{c.type} {c.name}={c.value_text}" for c in spec.constants]
        for field in spec.fields:
            lines.append(f"{indent}{field.type} {field.name}")
            if field.base_type not in BUILTIN_TYPES:
                lines.extend(self.show_lines(field.base_type, indent + "  "))
        return lines

    def message_names(self) -> list[str]:
        """Every message type known: source .msg files, the messages of .action files, built-ins."""
        names = set(self.source_names("msg"))
        for action in self.source_names("action"):
            names.update(f"{action}{suffix}" for suffix in ACTION_SUFFIXES)
        names.update(to_ros1_name(n) for n in builtin_store().fielddefs if "/msg/" in n)
        return sorted(names)


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise InterfaceError(f"cannot read {path}: {err}") from err


_catalogs: dict[tuple[str, ...], Interfaces] = {}


def interfaces(paths: Sequence[str | Path] = ()) -> Interfaces:
    """The catalog for these --interfaces paths (one per process and path list)."""
    key = tuple(str(p) for p in paths)
    if key not in _catalogs:
        _catalogs[key] = Interfaces(paths)
    return _catalogs[key]
