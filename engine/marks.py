"""Scan marks: what a watchdog outside the CPU's process reads to see a scan that hangs.

The CPU's process writes a few words into a buffer it shares with its supervisor
(``web/cli/supervisor.py``: a ``memfd`` both map): when the current cycle began (0 while
the scan thread waits for the next cycle), how many cycles have ended, the maximum cycle
time, the section of the cycle it is in (the scan, the plant) and the block it runs (set as
each OB, FB or FC is entered, put back as it returns). Each mark is one store into the
buffer; a hang in C code (``sum(range(10**13))``, a regular expression backtracking) holds
the interpreter's lock, so nothing in the process can act, but the marks written before it
say where it hangs and since when.

Names (blocks, sections) go once into a table of fixed slots after the header; a name that
finds no free slot is marked by its number alone. :class:`MarkReader` reads the same
buffer from the other side. ``GRACE_S`` and ``EXIT_HUNG`` are the rest of what the two
sides agree on: how long a stop request waits for a hanging scan, and the exit status of a
process that ended so.
"""

from __future__ import annotations

__all__ = ["EXIT_HUNG", "GRACE_S", "MARKS_SIZE", "MarkReader", "ScanMarks"]

GRACE_S = 3.0
"""How long a stop request waits for a hanging scan before the process ends anyway."""
EXIT_HUNG = 3
"""Exit status of a process ended because its scan did not return after a stop request."""

MARKS_SIZE = 4096
_HEADER = 64
_SLOT = 64
_SLOTS = (MARKS_SIZE - _HEADER) // _SLOT
_SCANS, _BUSY, _MAX_CYCLE, _SECTION, _BLOCK = range(5)


class ScanMarks:
    """The writing side, in the CPU's process (``buffer``: writable, ``MARKS_SIZE`` bytes)."""

    __slots__ = ("_names", "_next", "_raw", "_words")

    def __init__(self, buffer: memoryview | bytearray) -> None:
        raw = memoryview(buffer)
        if raw.nbytes < MARKS_SIZE or raw.readonly:
            raise ValueError(f"scan marks need {MARKS_SIZE} writable bytes")
        self._raw = raw
        self._words = raw[:_HEADER].cast("Q")
        self._names: dict[object, tuple[object, int]] = {}
        self._next = 1

    def max_cycle(self, ns: int) -> None:
        self._words[_MAX_CYCLE] = ns

    def begin(self, now_ns: int) -> None:
        """A cycle begins at ``now_ns`` (the monotonic clock, shared by every process)."""
        self._words[_BUSY] = now_ns

    def end(self) -> None:
        """The cycle's work is done (the scan thread waits for the next)."""
        words = self._words
        words[_SCANS] += 1
        words[_BUSY] = 0

    def section(self, what: str | None) -> None:
        self._words[_SECTION] = 0 if what is None else self._slot(what, what)

    def enter(self, block: object) -> int:
        """``block`` (with a ``label`` and a ``name``) runs; returns the mark to put back."""
        words = self._words
        before = words[_BLOCK]
        found = self._names.get(id(block))
        words[_BLOCK] = found[1] if found is not None else self._block_slot(block)
        return before

    def leave(self, before: int) -> None:
        self._words[_BLOCK] = before

    def _block_slot(self, block: object) -> int:
        label = str(getattr(block, "label", "?"))
        name = str(getattr(block, "name", "") or "")
        text = f'{label} "{name}"' if name and name != label else label
        return self._slot(id(block), text, keep=block)

    def _slot(self, key: object, text: str, keep: object = None) -> int:
        found = self._names.get(key)
        if found is not None:
            return found[1]
        slot = self._next
        if slot <= _SLOTS:
            data = text.encode("utf-8", "replace")[: _SLOT - 1]
            start = _HEADER + (slot - 1) * _SLOT
            self._raw[start : start + _SLOT] = data + bytes(_SLOT - len(data))
            self._next += 1
        else:
            slot = 0
        self._names[key] = (keep, slot)  # keeps ``block`` alive: its id stays its own
        return slot


class MarkReader:
    """The reading side, in the supervisor (``buffer``: ``MARKS_SIZE`` bytes)."""

    def __init__(self, buffer: memoryview | bytearray) -> None:
        self._raw = memoryview(buffer)
        self._words = self._raw[:_HEADER].cast("Q")

    def release(self) -> None:
        """Let go of the buffer (before it is closed)."""
        self._words.release()
        self._raw.release()

    @property
    def scans(self) -> int:
        return int(self._words[_SCANS])

    @property
    def busy_since_ns(self) -> int:
        """When the current cycle began (monotonic ns); 0 while no cycle runs."""
        return int(self._words[_BUSY])

    @property
    def max_cycle_ns(self) -> int:
        return int(self._words[_MAX_CYCLE])

    @property
    def section(self) -> str:
        return self._name(int(self._words[_SECTION]))

    @property
    def block(self) -> str:
        return self._name(int(self._words[_BLOCK]))

    def _name(self, slot: int) -> str:
        if not 1 <= slot <= _SLOTS:
            return ""
        start = _HEADER + (slot - 1) * _SLOT
        return bytes(self._raw[start : start + _SLOT]).split(b"\0", 1)[0].decode("utf-8", "replace")
