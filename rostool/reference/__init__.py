"""The ROS 1 / ROS 2 / rostool command reference behind `rostool cheatsheet`."""

from rostool.reference.model import (
    CheatsheetDataError,
    Entry,
    Misspelling,
    Reference,
    Section,
    default_reference,
    load_reference,
)
from rostool.reference.search import Hit, SearchResult, search

__all__ = [
    "CheatsheetDataError",
    "Entry",
    "Hit",
    "Misspelling",
    "Reference",
    "SearchResult",
    "Section",
    "default_reference",
    "load_reference",
    "search",
]
