"""Cyclone's sockets bound to 127.0.0.1 when discovery is localhost-only.

Cyclone DDS binds its unicast receive sockets to the any-address (0.0.0.0) whatever interface it is told
to use, and no setting changes that (eclipse-cyclonedds/cyclonedds#1923, #2090): with a localhost discovery
range rostool would still listen on every interface. Cyclone sends only to the 127.0.0.1 locators it
announces, so a socket bound to 127.0.0.1 receives all it needs. This module points libddsc's import of
`bind` (its GOT slot, found in the library's ELF relocations) at a function that turns an IPv4 any-address
into 127.0.0.1 and calls the real `bind`; everything else passes through unchanged. Where any step is not
possible (not Linux/ELF, no such relocation) it does nothing and Cyclone keeps its own binding.
"""

from __future__ import annotations

import contextlib
import ctypes
import struct
from pathlib import Path

_AF_INET = 2
_SHT_RELA, _SHT_DYNSYM = 4, 11
_R_GLOB_DAT, _R_JUMP_SLOT = 6, 7  # x86-64; aarch64 uses 1025/1026
_SLOT_TYPES = {_R_GLOB_DAT, _R_JUMP_SLOT, 1025, 1026}
_BIND = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int, ctypes.c_void_p, ctypes.c_uint32)
_patched: set[str] = set()
_keep: list[object] = []  # the callbacks must live as long as the process


def _relocation_offset(path: Path, symbol: bytes) -> int | None:
    """Where (relative to the load address) the ELF64 little-endian library at `path` keeps `symbol`'s
    address for its calls."""
    data = path.read_bytes()
    if data[:4] != b"\x7fELF" or data[4] != 2 or data[5] != 1:
        return None
    (shoff,) = struct.unpack_from("<Q", data, 0x28)
    entsize, count, _names = struct.unpack_from("<HHH", data, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * entsize) for i in range(count)]
    dynsym = next((s for s in sections if s[1] == _SHT_DYNSYM), None)
    if dynsym is None:
        return None
    strings = sections[dynsym[6]][4]
    for section in sections:
        if section[1] != _SHT_RELA:
            continue
        offset, size, step = section[4], section[5], section[9] or 24
        for index in range(size // step):
            where, info, _addend = struct.unpack_from("<QQq", data, offset + index * step)
            (name_at,) = struct.unpack_from("<I", data, dynsym[4] + (info >> 32) * 24)
            start = strings + name_at
            if data[start : data.index(b"\0", start)] == symbol and (info & 0xFFFFFFFF) in _SLOT_TYPES:
                return int(where)
    return None


def _loaded_libraries() -> dict[str, int]:
    """libddsc files mapped into this process, with their load addresses."""
    found: dict[str, int] = {}
    with open("/proc/self/maps", encoding="utf-8") as maps:
        for line in maps:
            fields = line.split()
            if len(fields) >= 6 and "/libddsc" in fields[-1]:
                start = int(fields[0].split("-")[0], 16)
                found[fields[-1]] = min(start, found.get(fields[-1], start))
    return found


def _writable(address: int) -> bool:
    with open("/proc/self/maps", encoding="utf-8") as maps:
        for line in maps:
            span, perms = line.split()[:2]
            start, end = (int(part, 16) for part in span.split("-"))
            if start <= address < end:
                return "w" in perms
    return False


def bind_to_loopback() -> None:
    """From now on, libddsc's IPv4 any-address binds go to 127.0.0.1 (once per process; best effort)."""
    import cyclonedds._clayer  # noqa: F401  (loads libddsc)

    libc = ctypes.CDLL(None, use_errno=True)
    real_bind = _BIND(("bind", libc))

    @_BIND
    def loopback_bind(fd: int, address: int, length: int) -> int:
        ipv4 = length >= 8 and ctypes.c_uint16.from_address(address).value == _AF_INET
        if ipv4 and ctypes.c_uint32.from_address(address + 4).value == 0:  # INADDR_ANY
            copy = ctypes.create_string_buffer(ctypes.string_at(address, length), length)
            ctypes.memmove(ctypes.addressof(copy) + 4, bytes((127, 0, 0, 1)), 4)
            return int(real_bind(fd, ctypes.addressof(copy), length))
        return int(real_bind(fd, address, length))

    with contextlib.suppress(OSError, ValueError, struct.error, IndexError):
        for path, base in _loaded_libraries().items():
            if path in _patched:
                continue
            offset = _relocation_offset(Path(path), b"bind")
            if offset is None or not _writable(base + offset):
                continue  # a read-only slot (full RELRO) is left alone: writing it would crash
            ctypes.c_void_p.from_address(base + offset).value = ctypes.cast(
                loopback_bind, ctypes.c_void_p
            ).value
            _patched.add(path)
            _keep.extend((loopback_bind, real_bind))
