"""The daemon's memory as its status reports it: the process's resident set, and what malloc has handed out
and not had back. Under churn the two tell a leak (both grow) from the allocator's fragmentation (only the
resident set grows)."""

from __future__ import annotations

import contextlib
import ctypes


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
        "keepcost",
    )]  # fmt: skip


def memory() -> dict[str, int]:
    """`rss_kib` (VmRSS) and, with glibc 2.33 or later, `malloc_in_use_kib` (every arena's chunks in use
    plus mmapped blocks; Python's small objects live in pymalloc's arenas, outside it)."""
    found: dict[str, int] = {}
    with contextlib.suppress(OSError, ValueError), open("/proc/self/status", encoding="utf-8") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                found["rss_kib"] = int(line.split()[1])
    with contextlib.suppress(OSError, AttributeError):
        mallinfo2 = ctypes.CDLL(None).mallinfo2
        mallinfo2.restype = _MallInfo2
        info = mallinfo2()
        found["malloc_in_use_kib"] = (info.uordblks + info.hblkhd) // 1024
    return found
