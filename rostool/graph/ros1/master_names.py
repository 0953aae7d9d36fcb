"""Graph-name rules the embedded master applies to what callers send.

Names are resolved against the caller id the way rosmaster does it: relative names go in the caller's
namespace, `~private` names under the caller id itself. The argument checks return rosmaster's messages.
"""

from __future__ import annotations

from typing import Any

SEP = "/"
ANY_TYPE = "*"


class ApiError(Exception):
    """An invalid argument: the API call answers [-1, message, <error value of the method>]."""


def canonicalize(name: str) -> str:
    """Drop repeated and trailing slashes: `//a//b/` -> `/a/b`."""
    if not name or name == SEP:
        return name
    parts = [part for part in name.split(SEP) if part]
    return (SEP if name[0] == SEP else "") + SEP.join(parts)


def namespace_of(name: str) -> str:
    """The namespace of a name, with a trailing slash: `/wg/node1` -> `/wg/`."""
    if not name:
        return SEP
    if name.endswith(SEP):
        name = name[:-1]
    return name[: name.rfind(SEP) + 1] or SEP


def join(namespace: str, name: str) -> str:
    if name.startswith(("~", SEP)):
        return name
    if not namespace:
        return name
    if namespace == "~":
        return "~" + name
    return namespace + name if namespace.endswith(SEP) else namespace + SEP + name


def resolve(name: str, caller_id: str) -> str:
    """Resolve `name` as seen by the node `caller_id` (global, relative or ~private)."""
    if not name:
        return namespace_of(caller_id)
    name = canonicalize(name)
    if name.startswith(SEP):
        return name
    if name.startswith("~"):
        return canonicalize(caller_id + SEP + name[1:])
    return namespace_of(caller_id) + name


# Argument checks. Each returns the canonical value or raises ApiError with rosmaster's message.


def key_arg(value: Any, label: str = "key") -> str:
    if not value:
        raise ApiError(f"ERROR: parameter [{label}] must be specified and non-empty")
    if not isinstance(value, str):
        raise ApiError(f"ERROR: parameter [{label}] must be a string")
    return value


def value_arg(value: Any, label: str = "value") -> Any:
    if value is None:
        raise ApiError(f"ERROR: parameter [{label}] must be specified")
    return value


def api_arg(value: Any, label: str) -> str:
    if not value or not isinstance(value, str):
        raise ApiError(f"ERROR: parameter [{label}] is not an XMLRPC URI")
    if not value.startswith(("http://", "rosrpc://")):
        raise ApiError(f"ERROR: parameter [{label}] is not an RPC URI")
    return value


def graph_name_arg(value: Any, caller_id: str, label: str) -> str:
    if not value or not isinstance(value, str):
        raise ApiError(f"ERROR: parameter [{label}] must be a non-empty string")
    # A colon is the usual sign of a URI sent where a name was expected.
    if ":" in value or " " in value:
        raise ApiError(f"ERROR: parameter [{label}] contains illegal chars")
    return resolve(value, caller_id)


def topic_arg(value: Any, caller_id: str, label: str) -> str:
    resolved = graph_name_arg(value, caller_id, label)
    if value == SEP:
        raise ApiError(f"ERROR: parameter [{label}] cannot be the global namespace")
    return resolved


def type_arg(value: Any, label: str = "topic_type") -> str:
    if value == ANY_TYPE:
        return ANY_TYPE
    if not value or not isinstance(value, str):
        raise ApiError(f"ERROR: parameter [{label}] must be a non-empty string")
    if len(value.split(SEP)) != 2:
        raise ApiError(f"ERROR: parameter [{label}] is not a valid package resource name")
    return value


def subgraph_arg(value: Any, caller_id: str, label: str = "subgraph") -> str:
    if not isinstance(value, str):
        raise ApiError(f"ERROR: parameter [{label}] must be a string")
    return resolve(value, caller_id) if value else ""
