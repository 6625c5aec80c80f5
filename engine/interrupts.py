"""OB priorities and cyclic interrupts OB30–OB38 (docs/runtime.md, "When a scan hangs or fails").

A cyclic OB runs every ``period`` measured on the CPU's process time from the STOP→RUN
transition, delayed by its phase offset (0 <= phase < period). Only loaded OBs have a
default period; a period of 0 deselects the OB. Events that fall while an OB is disabled
(SFC39 DIS_IRT) are lost, not queued; several events missed by a late scan run the OB once
and are reported as lost.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

CYCLIC_DEFAULT_MS: dict[int, int] = {
    30: 5000,
    31: 2000,
    32: 1000,
    33: 500,
    34: 200,
    35: 100,
    36: 50,
    37: 20,
    38: 10,
}
"""Default periods of OB30..OB38 (Siemens' Program Design for S7-300/400)."""

_MS = 1_000_000


def priority(ob: int) -> int:
    """Default priority class of an OB; OB121/122 take the faulting OB's class
    (``class_at_start``)."""
    if ob == 1:
        return 1
    if 10 <= ob <= 17:
        return 2
    if 20 <= ob <= 23:
        return ob - 17
    if 30 <= ob <= 38:
        return ob - 23
    if 40 <= ob <= 47:
        return ob - 24
    if 80 <= ob <= 87:
        return 26
    if 100 <= ob <= 102:
        return 27
    if ob == 90:
        return 29
    raise ValueError(f"OB{ob} has no fixed priority")


STARTUP_ERROR_CLASS = 28
"""The class OB80–OB87 run in during startup (26 in RUN)."""


def class_at_start(
    ob: int, *, faulting: int, startup: bool, priority_of: Callable[[int], int] = priority
) -> int:
    """The one rule for the priority class OB ``ob`` runs in when it starts: OB121/OB122 the
    class of the OB that caused them (``faulting``), OB80–OB87 28 during ``startup``, every
    other OB its own (``priority_of``: the CPU's parametrised classes, else ``priority``),
    0 for an OB without a class. The CPU stamps its diagnostic entries with it, and a
    diagnostic entry's requested OB is shown in it (``engine.diag_events``)."""
    if ob in (121, 122):
        return faulting
    if 80 <= ob <= 87 and startup:
        return STARTUP_ERROR_CLASS
    try:
        return priority_of(ob)
    except ValueError:
        return 0


@dataclass(slots=True)
class CyclicInterrupt:
    """Schedule of one cyclic-interrupt OB."""

    ob: int
    period_ns: int
    phase_ns: int = 0
    next_due_ns: int = 0
    enabled: bool = True
    lost: int = 0


class CyclicScheduler:
    """Due times of OB30..OB38 on the process time; ``due(now)`` yields the OBs to run."""

    def __init__(self) -> None:
        self._config: dict[int, tuple[int, int]] = {}
        self.active: dict[int, CyclicInterrupt] = {}

    def configure(self, ob: int, period_ms: int, phase_ms: int = 0) -> None:
        """Set an OB's period (0 = deselected) and phase offset, both whole ms."""
        if ob not in CYCLIC_DEFAULT_MS:
            raise ValueError(f"OB{ob} is not a cyclic interrupt OB (OB30..OB38)")
        if period_ms < 0 or not (0 <= phase_ms < max(period_ms, 1)):
            raise ValueError(f"OB{ob}: need 0 <= phase ({phase_ms}) < period ({period_ms})")
        self._config[ob] = (int(period_ms), int(phase_ms))

    def period_ms(self, ob: int) -> int:
        return self._config.get(ob, (CYCLIC_DEFAULT_MS[ob], 0))[0]

    def is_configured(self, ob: int) -> bool:
        """Explicitly configured with a non-zero period (as opposed to a default)."""
        return self._config.get(ob, (0, 0))[0] > 0

    def deselected(self) -> set[int]:
        return {ob for ob, (period, _) in self._config.items() if period == 0}

    def arm(self, obs: Iterable[int], t_run_ns: int) -> None:
        """Start the schedule at the STOP→RUN transition for the given OBs."""
        self.active.clear()
        for ob in sorted(set(obs)):
            period, phase = self._config.get(ob, (CYCLIC_DEFAULT_MS.get(ob, 0), 0))
            if ob not in CYCLIC_DEFAULT_MS or period <= 0:
                continue
            first = t_run_ns + (period + phase) * _MS
            self.active[ob] = CyclicInterrupt(ob, period * _MS, phase * _MS, first)

    def disable(self, ob: int) -> None:
        """SFC39 DIS_IRT mode 2: start events of ``ob`` are discarded."""
        if ob in self.active:
            self.active[ob].enabled = False

    def enable(self, ob: int) -> None:
        """SFC40 EN_IRT mode 2."""
        if ob in self.active:
            self.active[ob].enabled = True

    def due(self, now_ns: int) -> list[tuple[int, int]]:
        """OBs due at ``now_ns`` as ``(ob, lost_events)``, highest priority first."""
        return [(ob, lost) for ob, lost, _ in self.due_events(now_ns)]

    def due_events(self, now_ns: int) -> list[tuple[int, int, int]]:
        """OBs due at ``now_ns`` as ``(ob, lost_events, first_event_ns)``, highest OB first;
        the event time lets the CPU queue equal priorities in event order."""
        out: list[tuple[int, int, int]] = []
        for ob in sorted(self.active, reverse=True):
            ci = self.active[ob]
            if now_ns < ci.next_due_ns:
                continue
            first = ci.next_due_ns
            events = (now_ns - first) // ci.period_ns + 1
            ci.next_due_ns += events * ci.period_ns
            if ci.enabled:
                out.append((ob, events - 1, first))
                ci.lost += events - 1
        return out
