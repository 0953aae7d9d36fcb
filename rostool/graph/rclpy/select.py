"""Which ROS 2 backend serves a graph: rclpy (the user's own client library and RMW) or rostool's DDS.

`--ros2-backend auto|rclpy|dds`, else ROSTOOL_ROS2_BACKEND, else auto: rclpy when it imports, else DDS.
Nothing here imports rclpy until a graph is opened (or `doctor` asks), so `rostool --help` stays light.
A set RMW_IMPLEMENTATION is checked before rclpy is imported: librcl ends the process (exit 102) while
loading when the named RMW library is missing.
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from rostool.errors import RostoolError

BACKENDS = ("auto", "rclpy", "dds")
BACKEND_ENV = "ROSTOOL_ROS2_BACKEND"
WAY_OUT = "use --ros2-backend dds (rostool's own DDS, no rclpy needed)"


@dataclass(frozen=True)
class Choice:
    backend: str  # "rclpy" or "dds"
    asked: str  # "auto", "rclpy" or "dds"
    source: str  # where `asked` came from: the option, the variable or the default
    reason: str  # why `backend` serves the graph


def requested(explicit: str | None, env: Mapping[str, str] = os.environ) -> tuple[str, str]:
    """(auto|rclpy|dds, where it came from)."""
    if explicit:
        return explicit, "--ros2-backend"
    text = env.get(BACKEND_ENV, "").strip().lower()
    if not text:
        return "auto", "default"
    if text not in BACKENDS:
        raise RostoolError(f"{BACKEND_ENV}={text!r} is not valid: use one of {', '.join(BACKENDS)}")
    return text, BACKEND_ENV


def choose(explicit: str | None, env: Mapping[str, str] = os.environ) -> Choice:
    """The backend for a ROS 2 graph; a one-line error when rclpy was asked for and cannot serve."""
    from importlib.util import find_spec

    asked, source = requested(explicit, env)
    if asked == "dds":
        return Choice("dds", asked, source, f"asked for by {source}")
    if find_spec("rclpy") is None:
        missing = "rclpy is not installed in this Python: no sourced ROS 2, no rostool[ros2]"
        if asked == "auto":
            return Choice("dds", asked, source, f"auto: {missing}")
        raise RostoolError(f"the rclpy backend cannot start: {missing}; source a ROS 2 installation, "
                           f"pip install 'rostool[ros2]', or {WAY_OUT}")  # fmt: skip
    rmw = rmw_problem(env)
    if rmw is not None:
        raise RostoolError(f"{rmw}; or {WAY_OUT}")
    broken = import_problem()
    if broken is None:
        where = f"asked for by {source}" if asked == "rclpy" else "auto: rclpy imports"
        return Choice("rclpy", asked, source, where)
    if asked == "auto":
        return Choice("dds", asked, source, f"auto: {broken}")
    raise RostoolError(f"the rclpy backend cannot start: {broken}; {WAY_OUT}")


def import_problem() -> str | None:
    """None when `import rclpy` works, else what went wrong, in one line."""
    try:
        import rclpy  # noqa: F401
    except Exception as err:  # ImportError, OSError from a missing library, SyntaxError from a wrong Python
        text = " ".join(str(err).split()) or type(err).__name__
        missing = _MISSING_LIBRARY.search(text)
        if missing is not None:  # rclpy's C extension names the library first, then a long how-to
            library = missing[1]
            what = "the RMW library" if library.startswith("librmw_") else "the library"
            return (f"rclpy is present but {what} {library} is missing (not on LD_LIBRARY_PATH: is the ROS 2 "
                    "installation sourced, and its RMW installed?)")  # fmt: skip
        python = f"Python {sys.version_info.major}.{sys.version_info.minor}"
        return f"rclpy is present but does not import with {python} ({text})"
    return None


_MISSING_LIBRARY = re.compile(r"(\S+\.so[.\d]*): cannot open shared object file")


def rmw_problem(env: Mapping[str, str] = os.environ) -> str | None:
    """A set RMW_IMPLEMENTATION whose library the RMW loader would not find (it looks on LD_LIBRARY_PATH)."""
    name = env.get("RMW_IMPLEMENTATION", "").strip()
    if not name:
        return None
    if any((Path(d) / f"lib{name}.so").is_file() for d in library_dirs(env)):
        return None
    installed = installed_rmws(env)
    listed = f"installed: {', '.join(installed)}" if installed else "no RMW implementation found"
    return (f"RMW_IMPLEMENTATION={name!r} is not installed (no lib{name}.so on LD_LIBRARY_PATH; {listed}): "
            "unset it or name an installed one")  # fmt: skip


def library_dirs(env: Mapping[str, str] = os.environ) -> list[str]:
    return [d for d in env.get("LD_LIBRARY_PATH", "").split(os.pathsep) if d]


def prefixes(env: Mapping[str, str] = os.environ) -> list[Path]:
    """Install prefixes with an ament index: AMENT_PREFIX_PATH's, and this Python's (pip-installed ROS)."""
    found = [Path(p) for p in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    return [*found, Path(sys.prefix)]


def installed_rmws(env: Mapping[str, str] = os.environ) -> list[str]:
    """RMW implementations registered in the ament index (`rmw_typesupport`) whose library is loadable."""
    names: set[str] = set()
    for prefix in prefixes(env):
        index = prefix / "share" / "ament_index" / "resource_index" / "rmw_typesupport"
        if index.is_dir():
            names.update(p.name for p in index.iterdir())
    dirs = library_dirs(env)
    return sorted(n for n in names if any((Path(d) / f"lib{n}.so").is_file() for d in dirs))
