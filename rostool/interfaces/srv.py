"""ROS 1 service types: .srv text -> request and response types, with genmsg's service md5.

The built-in message store has no services, so the standard ones every graph has (std_srvs, and the
roscpp logger services each rospy/roscpp node offers) are defined here from their .srv text.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rostool.interfaces.msgspec import InterfaceError, MsgSpec, parse_srv
from rostool.interfaces.sources import read_source

if TYPE_CHECKING:
    from pathlib import Path

    from rostool.interfaces.ros1 import Ros1Type
    from rostool.interfaces.sources import Interfaces

_SUCCESS = "bool success   # indicate successful run of triggered service\n"
_MESSAGE = "string message # informational, e.g. for error messages\n"
BUILTIN_SRVS: dict[str, str] = {
    "std_srvs/Empty": "---",
    "std_srvs/Trigger": "---\n" + _SUCCESS + _MESSAGE,
    "std_srvs/SetBool": "bool data # e.g. for hardware enabling / disabling\n---\n" + _SUCCESS + _MESSAGE,
    "roscpp/Empty": "---\n",
    "roscpp/GetLoggers": "---\nLogger[] loggers\n",
    "roscpp/SetLoggerLevel": "string logger\nstring level\n---\n",
}


@dataclass(frozen=True)
class SrvType:
    """A service type: its name and md5 (what the service header carries) and both message types."""

    name: str  # pkg/Type
    md5sum: str
    request: Ros1Type
    response: Ros1Type
    request_spec: MsgSpec
    response_spec: MsgSpec
    text: str
    origin: str

    def request_args(self) -> str:
        """The request's field names, as `rosservice args` prints them."""
        return " ".join(field.name for field in self.request_spec.fields)

    def signature(self) -> str:
        """`a (int64), b (int64)`: what a caller has to give, in order."""
        return ", ".join(f"{field.name} ({field.type})" for field in self.request_spec.fields)


def service_type_name(name: str) -> str:
    """`pkg/Type` from `pkg/Type` or `pkg/srv/Type`."""
    parts = name.strip("/").split("/")
    if len(parts) == 3 and parts[1] == "srv":
        parts = [parts[0], parts[2]]
    if len(parts) != 2 or not all(parts):
        raise InterfaceError(f"{name!r} is not a service type; write it as package/Type")
    return "/".join(parts)


def load_service(catalog: Interfaces, name: str) -> SrvType:
    """The service type `pkg/Type` from the sources (see sources.py), else the standard ones above."""
    name = service_type_name(name)
    return catalog.built("srv", name, lambda path: _make_service(catalog, name, path))


def _make_service(catalog: Interfaces, name: str, path: Path | None) -> SrvType:
    if path is not None:
        text, origin = read_source(path), str(path)
    elif name in BUILTIN_SRVS:
        text, origin = BUILTIN_SRVS[name], f"built-in {name}.srv"
    else:
        raise catalog.not_found("srv", name)
    request, response = parse_srv(text, name, origin)
    catalog.add_specs({request.name: request, response.name: response})
    md5_text = request.md5_text(catalog.md5) + response.md5_text(catalog.md5)
    return SrvType(
        name,
        hashlib.md5(md5_text.encode()).hexdigest(),
        catalog.message(request.name),
        catalog.message(response.name),
        request,
        response,
        text,
        origin,
    )


def service_names(catalog: Interfaces) -> list[str]:
    return sorted(set(catalog.source_names("srv")) | set(BUILTIN_SRVS))
