"""Marker addresses for the global tags a TIA block export names without one.

A block export does not carry the PLC tag table, so a tag found neither in ``--symbols`` nor
with an informative address gets a marker address for the user to replace. The addresses
must lie in the CPU's marker area — ``M_BYTES`` bytes, the size ``engine.memory.Memory``
gives M — or the chart passes ``check`` and stops the CPU when it first touches one. The
rule: bits from M100.0 and bytes, words and double words (words and double words at even
bytes) from MB150, as long as they fit; then the lowest free bytes from MB16 up (MB0 …
MB15 are the retentive markers by default, which a tag must not silently become); never a
byte the chart already uses. When the area is full, ``take`` returns None: the importer
refuses the chart with a located error (I014) rather than write one the CPU cannot run.
"""

from __future__ import annotations

import inspect
import re
from typing import Final

from s7graph.engine.memory import Memory

__all__ = ["M_BYTES", "Markers", "used_bytes"]

M_BYTES: Final[int] = int(inspect.signature(Memory.__init__).parameters["markers"].default)
_FIRST_FREE: Final = 16  # MB0 … MB15 are retentive by default
_WIDTH: Final = {"": 1, "B": 1, "W": 2, "D": 4}
_M_ADDRESS: Final = re.compile(r"M([BWD]?)(\d+)(?:\.(\d))?", re.IGNORECASE)


def used_bytes(address: str) -> range:
    """The marker bytes an address occupies (empty for another area)."""
    m = _M_ADDRESS.fullmatch(address.replace(" ", ""))
    if m is None:
        return range(0)
    start = int(m.group(2))
    return range(start, start + _WIDTH[m.group(1).upper()])


class Markers:
    """The allocator of one import: ``used`` holds the bytes taken already."""

    def __init__(self, used: set[int], size: int = M_BYTES) -> None:
        self.size = size
        self.used = set(used)
        self.bit_byte: int | None = None  # the byte bits are being packed into
        self.bit = 8

    def take(self, width: str) -> str | None:
        """A free address of ``width`` ("" a bit, "B", "W", "D"), or None when M is full."""
        if width == "":
            if self.bit_byte is None or self.bit == 8:
                found = self.free(1, 100)
                if found is None:
                    return None
                self.bit_byte, self.bit = found, 0
            n, self.bit = self.bit, self.bit + 1
            return f"M{self.bit_byte}.{n}"
        byte = self.free(_WIDTH[width], 150)
        return None if byte is None else f"M{width}{byte}"

    def free(self, size: int, start: int) -> int | None:
        """The first run of ``size`` free bytes (even-aligned when wider than a byte) from
        ``start``, else from MB16; marked used."""
        step = 2 if size > 1 else 1
        for first in (start, _FIRST_FREE):
            n = first + (first % 2 if size > 1 else 0)
            while n + size <= self.size:
                if not any(b in self.used for b in range(n, n + size)):
                    self.used.update(range(n, n + size))
                    return n
                n += step
        return None
