"""The diagnostic buffer (Siemens' Program Design for S7-300/400, ch. 10).

Every entry carries the OB in which its event happened and that OB's priority class
(OB121/OB122 the class of the OB that caused them; 0 for the operating system's own
events outside every OB). A ring of fixed length: the newest entry overwrites the oldest.
The user program cannot clear it; it survives restarts and memory reset (it belongs to
the CPU, not to memory). Entries are numbered 1, 2, … in the order written, and keep their
number across restarts: a CPU that reads its buffer back from its state file numbers on
from the last entry written there.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator
from enum import IntEnum

from s7graph.engine.record import DiagEntry


class EventId(IntEnum):
    """Event ids 16#CEnn used by the runtime (Siemens' Program Design for S7-300/400, ch. 10;
    16#25FF is ours)."""

    STOP_TO_STARTUP = 0x4301
    STARTUP_TO_RUN = 0x4302
    STOP_BY_SWITCH = 0x4303
    STOP_BY_REQUEST = 0x4304
    HOLD_ENTERED = 0x4305
    HOLD_LEFT = 0x4306
    MEMORY_RESET = 0x4307
    STARTUP_REFUSED = 0x4309
    STOP_OB121_MISSING = 0x4562
    STOP_OB122_MISSING = 0x4563
    STOP_OB80_MISSING = 0x4564
    STOP_CYCLE_TIME = 0x4580
    STOP_OB82_MISSING = 0x4565
    STOP_OB83_MISSING = 0x4566
    STOP_OB84_MISSING = 0x4567
    STOP_OB85_MISSING = 0x4568
    STOP_OB87_MISSING = 0x4569
    STOP_OB86_MISSING = 0x456A
    STOP_STATE_WRITE = 0x45F0
    """Ours: the state file could not be written (disk full, I/O error)."""
    STOP_HUNG = 0x45F1
    """Ours: the process ended because a scan did not return after a stop request."""
    STOP_KILLED = 0x45F2
    """Ours: the supervisor ended a CPU process whose scan hung and brought it back in STOP."""
    CYCLE_TIME_EXCEEDED = 0x3501
    OB_REQUEST_ERROR = 0x3502
    STACK_OVERFLOW = 0x3574
    ASYNC_ERROR = 0x3900
    INTERRUPT_OB_MISSING = 0x35A1
    AREA_ERROR = 0x2524
    AREA_WRITE_ERROR = 0x2525
    IO_ACCESS_READ = 0x2942
    IO_ACCESS_WRITE = 0x2943
    DB_NOT_LOADED = 0x253A
    FC_NOT_LOADED = 0x253C
    FB_NOT_LOADED = 0x253E
    TYPE_ERROR = 0x2521
    PYTHON_EXCEPTION = 0x25FF
    COMMAND_FAILED = 0x5FFF
    SEQUENCER_POSITION = 0x5F01
    """Ours: a GRAPH FB's position, written before a warm or cold restart initializes it."""
    STATE_CARRIED_OVER = 0x5F02
    """Ours: a state file written for another version of a block, carried over."""
    FORCE_STARTED = 0x5F03
    """Ours: a force job set (or its value changed) on an address; it acts from this scan."""
    FORCE_ENDED = 0x5F04
    """Ours: force jobs deleted (unforce, or a memory reset); from this scan on they are gone."""
    USERS_FILE_EXPOSED = 0x5F05
    """Ours: the users file became readable by others; logins are refused until it is not."""
    USERS_FILE_PROTECTED = 0x5F06
    """Ours: the users file is no longer readable by others; logins are taken again."""
    STATE_RENEWED = 0x5F07
    """Ours: the state file was deleted, replaced or damaged while the CPU ran; it was
    written anew from the running CPU (``engine/renew.py``)."""
    STATE_NOT_TAKEN = 0x5F08
    """Ours: a run without ``--state`` started fresh though a state file beside its program
    holds a state: another program's passed over, or a renamed source's named."""


class DiagnosticBuffer:
    """A fixed-length ring of ``DiagEntry``: iteration oldest first, ``latest()`` newest first.

    ``wall``: the wall-clock time of a clock time (``SystemClock.wall_ns``), stamped on each
    entry ``record`` makes (None: a virtual clock, no wall time)."""

    __slots__ = ("_entries", "capacity", "ob", "priority", "total", "wall")

    def __init__(self, capacity: int = 100, *, wall: Callable[[int], int] | None = None) -> None:
        if capacity < 1:
            raise ValueError("a diagnostic buffer holds at least one entry")
        self.capacity = capacity
        self._entries: deque[DiagEntry] = deque(maxlen=capacity)
        self.total = 0
        """Entries ever added — to this CPU's state file, across restarts, once it was read
        back (``continue_from``): entry number ``total`` is the newest; the last
        ``total - n`` are new."""
        self.ob = 0
        self.priority = 0
        """The OB running now and its priority class (the CPU sets both around every OB):
        ``record`` stamps them on the entry; 0 outside every OB."""
        self.wall = wall

    def continue_from(self, total: int) -> None:
        """The entries held are the newest of ``total`` ever written (read back from the
        state file): number on from there, so an entry keeps its number across restarts."""
        self.total = max(self.total, total)

    def add(self, entry: DiagEntry) -> DiagEntry:
        self._entries.append(entry)
        self.total += 1
        return entry

    def record(
        self,
        t_ns: int,
        event_id: int,
        block: str = "",
        message: str = "",
        address: str = "",
        *,
        ob: int = 0,
    ) -> DiagEntry:
        """Append an entry built from its fields, stamped with the OB (``ob``, else the
        running one), its priority class and its wall-clock time, and return it."""
        wall = self.wall(t_ns) if self.wall is not None else 0
        entry = DiagEntry(
            t_ns, int(event_id), block, message, address, ob or self.ob, self.priority, wall
        )
        return self.add(entry)

    def since(self, total: int) -> tuple[DiagEntry, ...]:
        """Entries added after the buffer's ``total`` was ``total`` (at most ``capacity``)."""
        n = min(self.total - total, len(self._entries))
        if n <= 0:
            return ()
        return tuple(self._entries)[-n:]

    def latest(self) -> list[DiagEntry]:
        """Newest first, as a programming device lists them (No. 1 = newest)."""
        return list(reversed(self._entries))

    def __iter__(self) -> Iterator[DiagEntry]:
        return iter(tuple(self._entries))

    def __len__(self) -> int:
        return len(self._entries)
