"""One table: restart type → startup OB and what each keeps or clears (docs/runtime.md, "Restarts:
warm, hot, cold").

Siemens' Program Design for S7-300/400, ch. 9 / Table 9-4. ``True`` in a ``clear_*`` column means
the area is reset; DBs are "reloaded" from their load-memory initial values.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum

from s7graph.engine.diagnostics import EventId
from s7graph.engine.record import DiagEntry


class RestartType(StrEnum):
    """Startup types: warm (OB100), hot (OB101), cold (OB102)."""

    WARM = "warm"
    HOT = "hot"
    COLD = "cold"


@dataclass(frozen=True, slots=True)
class RestartRule:
    """What one startup type does to memory before its startup OB runs."""

    ob: int
    clear_nonretentive_mtc: bool
    clear_retentive_mtc: bool
    reload_dbs: bool
    """Global DBs and instance DBs back to their initial values."""
    delete_runtime_dbs: bool
    """DBs created at run time (SFC22), not by a download, are deleted."""
    clear_piq: bool
    clear_pii: bool
    residual_cycle: bool


RESTART: dict[RestartType, RestartRule] = {
    RestartType.WARM: RestartRule(
        ob=100,
        clear_nonretentive_mtc=True,
        clear_retentive_mtc=False,
        reload_dbs=False,
        delete_runtime_dbs=False,
        clear_piq=True,
        clear_pii=True,
        residual_cycle=False,
    ),
    RestartType.HOT: RestartRule(
        ob=101,
        clear_nonretentive_mtc=False,
        clear_retentive_mtc=False,
        reload_dbs=False,
        delete_runtime_dbs=False,
        clear_piq=True,  # after the residual cycle unless "keep outputs at hot restart"
        clear_pii=False,
        residual_cycle=True,
    ),
    RestartType.COLD: RestartRule(
        ob=102,
        clear_nonretentive_mtc=True,
        clear_retentive_mtc=True,
        reload_dbs=True,
        delete_runtime_dbs=True,
        clear_piq=True,
        clear_pii=True,
        residual_cycle=False,
    ),
}


HOT_RESTART_BLOCKERS: tuple[str, ...] = (
    "memory reset",
    "program download",
    "stack overflow",
    "aborted warm restart",
)
"""Causes after which only a warm restart is allowed (Siemens' Program Design for S7-300/400)."""


HOT_AFTER_STOP: frozenset[int] = frozenset(
    {
        EventId.STOP_BY_SWITCH,
        EventId.STOP_BY_REQUEST,
        EventId.STOP_OB121_MISSING,
        EventId.STOP_OB80_MISSING,
        EventId.STOP_OB82_MISSING,
        EventId.STOP_OB83_MISSING,
        EventId.STOP_OB84_MISSING,
        EventId.STOP_OB85_MISSING,
        EventId.STOP_OB86_MISSING,
        EventId.STOP_OB87_MISSING,
    }
)
"""STOPs after which a manual hot restart is possible (S7-400, "Programming with STEP 7",
Operating Modes: the mode selector, a programmed STOP, an OB not loaded, a programming
device's or a communication function's STOP)."""
NO_HOT_AFTER_STOP: frozenset[int] = frozenset(
    {
        EventId.STOP_CYCLE_TIME,
        EventId.STACK_OVERFLOW,
        EventId.STOP_STATE_WRITE,
        EventId.STOP_HUNG,
        EventId.STOP_KILLED,
    }
)
"""STOPs by an error after which only a warm restart is possible: a block aborted by cycle
monitoring, a stack overflow, a state file not written, a scan that did not return (also
when the supervisor ended the process for it)."""


def stop_blocker(entries: Iterable[DiagEntry]) -> str | None:
    """Why the last STOP in ``entries`` (a diagnostic buffer, oldest first) allows no hot
    restart, or None: it allows one, or the CPU was in RUN (a power cut)."""
    for entry in reversed(list(entries)):
        if entry.event_id == EventId.STARTUP_TO_RUN or entry.event_id in HOT_AFTER_STOP:
            return None
        if entry.event_id in NO_HOT_AFTER_STOP:
            return error_blocker(entry.message)
    return None


def error_blocker(message: str) -> str:
    """The hot restart blocker a STOP by an error (``NO_HOT_AFTER_STOP``) leaves, saying
    ``message``: the same words whether the CPU holds it or a state file gives it back."""
    return f"STOP by an error ({message})"


def parse_restart(text: str | RestartType) -> RestartType:
    """``'warm'``/``'hot'``/``'cold'`` (any case) as a ``RestartType``; ValueError otherwise."""
    try:
        return RestartType(str(text).lower())
    except ValueError:
        raise ValueError(f"unknown restart type {text!r} (warm, hot or cold)") from None
