"""Optional libraries of the `plot` extra (matplotlib, networkx, plotext), imported only when used."""

from __future__ import annotations

import importlib
from typing import Any

from rostool.errors import RostoolError


def need(module: str, extra: str = "plot") -> Any:
    """The module, or one line naming the extra that brings it."""
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise RostoolError(f"{module} is not installed: pip install 'rostool[{extra}]'") from err
