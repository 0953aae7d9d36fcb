"""Where a user's daemons live, and which daemon serves an environment.

Sockets and locks go in a directory only the user can enter: `$ROSTOOL_RUNTIME_DIR`, else
`$XDG_RUNTIME_DIR/rostool`, else `/tmp/rostool-<uid>`; it is created 0700 and refused (one line) when it is
a symlink, another user's, or open to others. Logs go in `$XDG_STATE_HOME/rostool` (`~/.local/state`).

One daemon per key: the environment variables that decide which graph a ROS 2 process sees (domain,
discovery range and peers, RMW and its profiles, security), the network namespace, the backend asked for and
the interpreter.
The build (rostool's version and its sources' modification times) is not part of the key: a daemon of
another build is told to stop and replaced.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import stat
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from rostool.errors import RostoolError

KEY_VARIABLES = (
    "ROS_DOMAIN_ID", "RMW_IMPLEMENTATION", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS",
    "ROS_LOCALHOST_ONLY", "FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE",
    "CYCLONEDDS_URI", "ZENOH_ROUTER_CONFIG_URI", "ZENOH_SESSION_CONFIG_URI", "ROS_SECURITY_ENABLE",
    "ROS_SECURITY_STRATEGY", "ROS_SECURITY_KEYSTORE", "ROS_SECURITY_ENCLAVE_OVERRIDE", "ROS_DISTRO",
    "AMENT_PREFIX_PATH",
)  # fmt: skip
BUILD_ENV = "ROSTOOL_DAEMON_BUILD"  # the build a daemon claims (tests: a daemon of another build)


class PlaceRefused(RostoolError):
    """The daemon's directory or socket is not private to this user."""


@dataclass(frozen=True)
class DaemonPlace:
    """The files of the daemon that serves one key."""

    name: str  # e.g. dds-d17-1a2b3c4d5e
    socket: Path
    lock: Path
    log: Path
    fields: tuple[tuple[str, str], ...]  # what the key is made of, for `daemon status`


def runtime_dir(env: Mapping[str, str] = os.environ) -> Path:
    explicit = env.get("ROSTOOL_RUNTIME_DIR", "").strip()
    if explicit:
        return Path(explicit)
    xdg = env.get("XDG_RUNTIME_DIR", "").strip()
    if xdg and Path(xdg).is_dir():
        return Path(xdg) / "rostool"
    return Path(f"/tmp/rostool-{os.getuid()}")


def state_dir(env: Mapping[str, str] = os.environ) -> Path:
    xdg = env.get("XDG_STATE_HOME", "").strip()
    base = Path(xdg) if xdg else Path(env.get("HOME") or Path.home()) / ".local" / "state"
    return base / "rostool"


def private_dir(path: Path, create: bool = True) -> Path:
    """`path`, made 0700 when missing; refused when it is not a directory only this user can enter."""
    if create:
        path.parent.mkdir(parents=True, exist_ok=True)
        with contextlib.suppress(FileExistsError):
            path.mkdir(mode=0o700)
    try:
        info = path.lstat()
    except FileNotFoundError:
        return path
    if not stat.S_ISDIR(info.st_mode):
        raise PlaceRefused(f"{path} is not a directory (the graph daemon's socket directory): remove it")
    if info.st_uid != os.getuid():
        raise PlaceRefused(
            f"{path} belongs to uid {info.st_uid}, not to you (uid {os.getuid()}): the graph daemon refuses "
            "it; remove it or set ROSTOOL_RUNTIME_DIR to a directory of yours"
        )
    if info.st_mode & 0o077:
        raise PlaceRefused(
            f"{path} is open to other users (mode {stat.S_IMODE(info.st_mode):o}): the graph daemon refuses "
            f"it; run `chmod 700 {path}`"
        )
    return path


def key_fields(backend: str, env: Mapping[str, str] = os.environ) -> tuple[tuple[str, str], ...]:
    from rostool.graph.ros2_base.env import domain_id

    fields = [("backend", backend), ("domain", str(domain_id(env))), ("python", sys.executable)]
    network = network_namespace()
    if network:
        fields.append(("network", network))
    fields += [(name, env[name]) for name in KEY_VARIABLES if name != "ROS_DOMAIN_ID" and env.get(name)]
    return tuple(fields)


def network_namespace() -> str:
    """This process's network namespace (`net:[4026531840]`), or "" where there is none to read: two
    containers or namespaces that share /tmp see different networks, so they must never share a daemon."""
    try:
        return os.readlink("/proc/self/ns/net")
    except OSError:
        return ""


def daemon_place(backend: str, env: Mapping[str, str] = os.environ, create: bool = True) -> DaemonPlace:
    """The socket, lock and log of the daemon for `backend` (auto, rclpy or dds) in this environment."""
    fields = key_fields(backend, env)
    digest = hashlib.sha256(json.dumps(fields).encode()).hexdigest()[:10]
    name = f"{backend}-d{dict(fields)['domain']}-{digest}"
    run = private_dir(runtime_dir(env), create)
    log = state_dir(env) / f"{name}.log"
    return DaemonPlace(name, run / f"{name}.sock", run / f"{name}.lock", log, fields)


def build_id(env: Mapping[str, str] = os.environ) -> str:
    """rostool's version and the newest modification time of its graph sources (what the daemon runs): a
    changed checkout (an editable install) is another build, and its daemon is replaced."""
    from rostool import __version__

    claimed = env.get(BUILD_ENV, "").strip()
    if claimed:
        return claimed
    root = Path(__file__).resolve().parents[1]
    newest = 0
    for folder, _dirs, files in os.walk(root):
        for file in files:
            if file.endswith(".py"):
                newest = max(newest, os.stat(os.path.join(folder, file)).st_mtime_ns)
    return f"{__version__}+{newest}"
