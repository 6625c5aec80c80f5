"""What a programming device shows of a diagnostic entry (STEP 7's "Module Information →
Diagnostic Buffer"; Siemens' Program Design for S7-300/400, ch. 10): the event's text, the
OB the event requests and the priority class it runs in, and the error entry that caused a
STOP (docs/runtime.md, "The diagnostic buffer").

The texts are STEP 7's where the event is S7's, in its words where s7graph means the same;
the events that are s7graph's own (``16#25FF``, ``16#45Fx``, ``16#5Fxx``) say what they are.
An event ID the table does not hold gets the text of its class (``16#25xx`` a programming
error, ``16#35xx`` a time error …).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable

from s7graph.engine.cpu_interrupts import MISSING_STOP
from s7graph.engine.diagnostics import EventId
from s7graph.engine.interrupts import class_at_start, priority
from s7graph.engine.record import DiagEntry

__all__ = [
    "EVENT_TEXTS",
    "event_text",
    "hex_id",
    "last_error_stop",
    "priority_class",
    "requested_ob",
    "stop_cause",
]

EVENT_TEXTS: dict[int, str] = {
    EventId.TYPE_ERROR: "Type error: a value that does not fit its type",
    0x2522: "Area length error when reading",
    0x2523: "Area length error when writing",
    EventId.AREA_ERROR: "Area error: an address outside the operand areas",
    EventId.DB_NOT_LOADED: "DB not loaded",
    EventId.FC_NOT_LOADED: "FC not loaded",
    EventId.FB_NOT_LOADED: "FB not loaded",
    EventId.PYTHON_EXCEPTION: "Programming error: a Python exception in a block",
    EventId.CYCLE_TIME_EXCEEDED: "Cycle time exceeded",
    EventId.OB_REQUEST_ERROR: "OB request error: start events lost",
    EventId.STACK_OVERFLOW: "Block stack overflow (nesting depth exceeded)",
    EventId.INTERRUPT_OB_MISSING: "User interface (OB) not found: an interrupt OB not loaded",
    EventId.STOP_TO_STARTUP: "Mode transition from STOP to STARTUP",
    EventId.STARTUP_TO_RUN: "Mode transition from STARTUP to RUN",
    EventId.STOP_BY_SWITCH: "STOP caused by the mode selector (key switch) set to STOP",
    EventId.STOP_BY_REQUEST: "STOP caused by a PG STOP operation (the RUN/STOP switch, SFC46)",
    EventId.HOLD_ENTERED: "HOLD: breakpoint reached",
    EventId.HOLD_LEFT: "HOLD: breakpoint exited",
    EventId.MEMORY_RESET: "Memory reset started by a PG operation",
    EventId.STARTUP_REFUSED: "Startup refused or changed",
    EventId.STOP_OB121_MISSING: "STOP caused by a programming error (OB121 not loaded)",
    EventId.STOP_OB80_MISSING: "STOP caused by a time error (OB80 not loaded)",
    EventId.STOP_CYCLE_TIME: "STOP caused by cycle monitoring: a block aborted",
    EventId.STOP_OB82_MISSING: "STOP caused by a diagnostic interrupt (OB82 not loaded)",
    EventId.STOP_OB83_MISSING: "STOP caused by an insert/remove interrupt (OB83 not loaded)",
    EventId.STOP_OB84_MISSING: "STOP caused by a CPU hardware error (OB84 not loaded)",
    EventId.STOP_OB85_MISSING: "STOP caused by a program sequence error (OB85 not loaded)",
    EventId.STOP_OB87_MISSING: "STOP caused by a communication error (OB87 not loaded)",
    EventId.STOP_OB86_MISSING: "STOP caused by a rack failure (OB86 not loaded)",
    EventId.STOP_STATE_WRITE: "STOP: the state file could not be written",
    EventId.STOP_HUNG: "STOP: a scan did not return after a stop request",
    EventId.STOP_KILLED: "STOP: the supervisor ended the CPU process, its scan hung",
    EventId.COMMAND_FAILED: "A command failed at the scan boundary",
    EventId.SEQUENCER_POSITION: "S7-GRAPH sequencer position",
    EventId.STATE_CARRIED_OVER: "State carried over to a changed block",
    EventId.FORCE_STARTED: "Force job started",
    EventId.FORCE_ENDED: "Force jobs deleted",
    EventId.STOP_OB122_MISSING: "STOP caused by an I/O access error (OB122 not loaded)",
    EventId.AREA_WRITE_ERROR: "Area error when writing",
    EventId.IO_ACCESS_READ: "I/O access error when reading",
    EventId.IO_ACCESS_WRITE: "I/O access error when writing",
    EventId.USERS_FILE_EXPOSED: "The users file is readable by others: logins refused",
    EventId.USERS_FILE_PROTECTED: "The users file is private again: logins taken",
    EventId.STATE_RENEWED: "State file written anew: it was deleted or damaged",
    EventId.STATE_NOT_TAKEN: "A state file beside the program not taken: a fresh start",
}
"""The text of each event ID the runtime writes."""

_CLASS_TEXTS: dict[int, str] = {
    0x25: "Programming error",
    0x35: "Time error",
    0x39: "Asynchronous error",
    0x43: "Mode transition",
    0x45: "STOP",
    0x5F: "s7graph event",
}
_OB = re.compile(r"OB(\d{1,3})$")
STARTUP_OBS = frozenset({100, 101, 102})  # an event in one of them happened in startup
_MISSING: dict[int, int] = {int(event): ob for ob, event in MISSING_STOP.items()}
_MISSING[EventId.STOP_OB121_MISSING] = 121
_MISSING[EventId.STOP_OB122_MISSING] = 122


def hex_id(event_id: int) -> str:
    """The event ID as STEP 7 writes it: ``16#4302``."""
    return f"16#{event_id & 0xFFFF:04X}"


def event_text(event_id: int) -> str:
    """The text of ``event_id`` (the text of its class when the table has none)."""
    text = EVENT_TEXTS.get(event_id)
    if text is not None:
        return text
    if event_id >> 4 == EventId.ASYNC_ERROR >> 4:
        return f"Asynchronous error for OB{80 + (event_id & 0xF)}"
    return _CLASS_TEXTS.get(event_id >> 8, "Event")


def _named_ob(block: str) -> int:
    m = _OB.match(block)
    return int(m[1]) if m else 0


def requested_ob(entry: DiagEntry) -> int:
    """The OB the event requests (STEP 7's "Requested OB"): OB121 for a programming error,
    OB122 for an I/O access error, OB80 for a time error, OB8x for an asynchronous error,
    the startup OB of a STOP → STARTUP transition, the error OB not loaded of a STOP; 0 for
    none."""
    event = entry.event_id
    if event >> 8 == 0x25:
        return 121
    if event >> 8 == 0x29:  # an I/O access error
        return 122
    if event == EventId.INTERRUPT_OB_MISSING:
        return 85
    if event in (EventId.CYCLE_TIME_EXCEEDED, EventId.OB_REQUEST_ERROR):
        return 80
    if event >> 4 == EventId.ASYNC_ERROR >> 4:
        return 80 + (event & 0xF)
    if event == EventId.STOP_TO_STARTUP:
        return _named_ob(entry.block)
    return _MISSING.get(event, 0)


def priority_class(entry: DiagEntry, priority_of: Callable[[int], int] = priority) -> int:
    """The priority class the requested OB runs in (0: no OB), by the CPU's own rule
    (``interrupts.class_at_start``): OB121/OB122 in the class of the OB whose program
    faulted — the class the entry records (``entry.priority``; that of ``entry.ob``, or of
    OB1, for an entry without one) —, OB80–OB87 in 28 for an event of a startup OB.
    ``priority_of``: the CPU's (``Cpu.priority_of``, its parametrised classes)."""
    ob = requested_ob(entry)
    if ob == 0:
        return 0
    faulting = entry.priority or class_at_start(
        entry.ob or 1, faulting=0, startup=False, priority_of=priority_of
    )
    startup = entry.ob in STARTUP_OBS
    return class_at_start(ob, faulting=faulting, startup=startup, priority_of=priority_of)


def stop_cause(entries: Iterable[DiagEntry], stop: DiagEntry) -> DiagEntry | None:
    """The error entry right before the STOP entry ``stop`` (a programming error 16#25xx, a
    time error 16#35xx) that caused it, or None: the STOP was its own cause (the switch, a
    missing OB, the supervisor) or ``stop`` is no longer in ``entries``."""
    before: DiagEntry | None = None
    for entry in entries:
        if entry is stop:
            if before is not None and before.event_id >> 12 in (0x2, 0x3):
                return before
            return None
        before = entry
    return None


_LEFT_STOP = frozenset({EventId.STARTUP_TO_RUN, EventId.STOP_BY_SWITCH, EventId.STOP_BY_REQUEST})
"""Events after which the buffer's last STOP by an error is no longer why the CPU stopped."""


def last_error_stop(entries: Iterable[DiagEntry]) -> str | None:
    """Why the CPU stopped, when its last STOP (in ``entries``, a diagnostic buffer oldest
    first) was one by an error (``16#45xx``) it has not restarted from since: the STOP
    entry's message, after the error entry that caused it (``stop_cause``); None otherwise
    (it stopped by the switch or a request, or it was in RUN: a power cut)."""
    held = list(entries)
    for entry in reversed(held):
        if entry.event_id in _LEFT_STOP:
            return None
        if entry.event_id >> 8 == 0x45:
            cause = stop_cause(held, entry)
            if cause is None:
                return _said(entry)
            return f"{_said(cause)} ({entry.message})"
    return None


def _said(entry: DiagEntry) -> str:
    return f"{entry.block}: {entry.message}" if entry.block else entry.message
