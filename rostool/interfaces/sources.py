"""ROS 1 interface definitions from source trees (.msg/.srv/.action): found, parsed (msgspec.py) and
hashed as genmsg does.

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
from typing import TYPE_CHECKING, Any, TypeVar, cast

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

if TYPE_CHECKING:
    from rosbags.interfaces.typing import Typesdict
    from rosbags.typesys.store import Typestore

import rostool.interfaces.rosbags_fix  # noqa: F401 - must run before types are registered
from rostool.interfaces.describe import describe
from rostool.interfaces.msgspec import (
    ACTION_SUFFIXES,
    BUILTIN_TYPES,
    InterfaceError,
    MsgSpec,
    load_action_specs,
    parse_msg,
    parse_srv,
)
from rostool.interfaces.names import to_ros1_name, to_store_name
from rostool.interfaces.ros1 import Ros1Type, builtin_store

_SEPARATOR = "=" * 80
_IGNORE_MARKERS = ("CATKIN_IGNORE", "COLCON_IGNORE", "AMENT_IGNORE")
_CRAWL_DEPTH = 6
_CRAWL_LIMIT = 20_000  # folders visited per root
KINDS = ("msg", "srv", "action")
INTERFACES_ENV = "ROSTOOL_INTERFACES"
T = TypeVar("T")


def interface_paths_from_env() -> tuple[str, ...]:
    """ROSTOOL_INTERFACES split as click splits it for --interfaces (at os.pathsep): verbs without the
    option (topic echo) find custom types there too."""
    value = os.environ.get(INTERFACES_ENV, "")
    return tuple(p for p in value.split(os.pathsep) if p.strip())


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
        self._built: dict[tuple[str, str], Any] = {}  # services and actions made from these types

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

    def built(self, kind: str, name: str, make: Callable[[Path | None], T]) -> T:
        """The service or action type `name` (`kind` srv or action), made once by `make(its source file
        or None)`."""
        key = (kind, name)
        if key not in self._built:
            package, _, short = name.partition("/")
            self._built[key] = make(self.find_file(package, kind, short))
        return cast("T", self._built[key])

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
            return parse_msg(read_source(path), name, str(path))
        for suffix in ("Request", "Response"):  # the two halves of a .srv are messages too (as in genpy)
            base = short[: -len(suffix)]
            srv_path = self.find_file(package, "srv", base) if short.endswith(suffix) and base else None
            if srv_path is not None:
                request, response = parse_srv(read_source(srv_path), f"{package}/{base}", str(srv_path))
                self.add_specs({request.name: request, response.name: response})
                return self._specs.get(name)
        for suffix in ACTION_SUFFIXES:
            base = short[: -len(suffix)]
            action_path = self.find_file(package, "action", base) if short.endswith(suffix) and base else None
            if action_path is not None:
                specs = load_action_specs(read_source(action_path), f"{package}/{base}", str(action_path))
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


def read_source(path: Path) -> str:
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
