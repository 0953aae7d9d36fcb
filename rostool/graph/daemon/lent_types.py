"""`LentTypes`: the types a DaemonGraph lends its verb before a direct graph exists (a relayed subscription
needs none), shared with the direct graph once one is made. Its own module: the type store it imports is
not needed before a cold verb's discovery has started."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rostool.interfaces.ros2_types import Ros2Types


class LentTypes(Ros2Types):
    """Types made before the direct graph; once it is made, its types and these share one store, so what
    either registers (a bag's types, a service's, one learned from a publisher) both know, and a renderer
    made with these (echo's, service call's field lookup) sees it."""

    _also: Ros2Types | None = None

    def lend_to(self, other: Ros2Types) -> None:
        """`other`: the direct graph's types, just made (nothing of theirs holds their store yet)."""
        self.register(_missing(other, self))
        if other.distro == self.distro:
            other.store = self.store
            return
        # another distro than the daemon's (not one key): each keeps its store, ours passed on as we go
        other.register(_missing(self, other))
        self._also = other

    def register(self, typs: Mapping[str, Any]) -> None:
        super().register(typs)
        if self._also is not None:
            self._also.register(typs)


def _missing(source: Ros2Types, target: Ros2Types) -> dict[str, Any]:
    return {name: defs for name, defs in source.store.fielddefs.items() if not target.in_store(name)}
