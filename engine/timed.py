"""Delay interrupts OB20–OB23 and time-of-day interrupts OB10–OB17 (Siemens' Program Design for
S7-300/400, ch. 3-4; STEP7 comprehensive guide vol. 2, ch. 12).

Delay interrupts (STEP7 comprehensive guide vol. 2, ch. 12): SFC32 SRT_DINT starts a one-shot delay
on the CPU's *process* time (frozen in HOLD); when it elapses the OB runs once with the
caller's SIGN; SFC33 cancels; SFC34 status bit 2 is 1 while pending.

Time-of-day interrupts (STEP7 comprehensive guide vol. 2, ch. 12; Siemens' Program Design for
S7-300/400) run on the CPU's real-time clock (``engine.rtc``), never the wall clock. SFC28 SET_TINT
sets start and period but does not activate; SFC30 ACT_TINT activates; a warm or cold restart
deactivates program-activated interrupts (``configure(..., active=True)`` ones — the HW-config
"Active" box — come back by themselves). A periodic interrupt whose start day does not exist in a
month/year is skipped there (Siemens' Program Design for S7-300/400). The CPU checks due interrupts
only in RUN, so one due during STARTUP runs after the transition to RUN.
"""

from __future__ import annotations

import calendar
from dataclasses import dataclass
from datetime import datetime, timedelta
from enum import IntEnum

DELAY_OBS = range(20, 24)
TOD_OBS = range(10, 18)
NS_PER_MS = 1_000_000
DTIME_MAX_MS = 60_000  # [K] S7-300: DTIME 1 .. 60000 ms

# RET_VAL words (as 16-bit words; callers convert to INT).
OK = 0
WRONG_OB = 0x8090
WRONG_DTIME = 0x8091  # SRT_DINT: DTIME out of range; SET_TINT: invalid SDT
WRONG_PERIOD = 0x8092
NOT_SET = 0x80A0  # CAN_DINT: not started; ACT_TINT/CAN_TINT: no start time set
IN_THE_PAST = 0x80A1  # ACT_TINT: once-only start time already passed

# Status bits of SFC31 QRY_TINT / SFC34 QRY_DINT (STEP7 comprehensive guide vol. 2, ch. 12).
ST_DISABLED = 0x01
ST_PENDING = 0x04
ST_LOADED = 0x10


class Period(IntEnum):
    """SFC28 PERIOD codes (STEP7 comprehensive guide vol. 2, ch. 12)."""

    ONCE = 0x0000
    MINUTE = 0x0201
    HOUR = 0x0401
    DAY = 0x1001
    WEEK = 0x1202
    MONTH = 0x1401
    YEAR = 0x1801
    MONTH_END = 0x2001


_FIXED = {
    Period.MINUTE: timedelta(minutes=1),
    Period.HOUR: timedelta(hours=1),
    Period.DAY: timedelta(days=1),
    Period.WEEK: timedelta(weeks=1),
}


def _month_shift(start: datetime, months: int, *, month_end: bool) -> datetime | None:
    y, m = divmod(start.month - 1 + months, 12)
    year, month = start.year + y, m + 1
    last = calendar.monthrange(year, month)[1]
    if month_end:
        return start.replace(year=year, month=month, day=last)
    if start.day > last:
        return None  # 31 Jan monthly: only months with 31 days (Program Design)
    return start.replace(year=year, month=month)


def next_occurrence(start: datetime, period: int, at_or_after: datetime) -> datetime | None:
    """The first occurrence of the series ``start, start + period, …`` at or after the given
    time; None for a once-only interrupt whose start has passed."""
    code = Period(period)
    if code is Period.ONCE:
        return start if start >= at_or_after else None
    step = _FIXED.get(code)
    if step is not None:
        if start >= at_or_after:
            return start
        k = -((start - at_or_after) // step)  # ceil((at_or_after - start) / step)
        return start + k * step
    months = 12 if code is Period.YEAR else 1
    end = code is Period.MONTH_END
    first = _month_shift(start, 0, month_end=end)
    n = 0
    if first is not None and first < at_or_after:
        n = max(0, (at_or_after.year - start.year) * 12 + at_or_after.month - start.month - 1)
        n -= n % months
    for k in range(n, n + 12 * 8 + 1, months):  # leap days recur within 8 years
        when = _month_shift(start, k, month_end=end)
        if when is not None and when >= at_or_after:
            return when
    return None


@dataclass(slots=True)
class DelayInterrupt:
    """One started delay: due on the process time, with the caller's SIGN word."""

    ob: int
    due_ns: int
    sign: int


class DelayInterrupts:
    """OB20–OB23 started by SFC32, cancelled by SFC33, queried by SFC34."""

    def __init__(self) -> None:
        self.pending: dict[int, DelayInterrupt] = {}

    def start(self, ob: int, dtime_ms: int, sign: int, now_ns: int) -> int:
        """SFC32 SRT_DINT: (re)start the delay of ``ob``; RET_VAL word."""
        if ob not in DELAY_OBS:
            return WRONG_OB
        if not 1 <= dtime_ms <= DTIME_MAX_MS:
            return WRONG_DTIME
        self.pending[ob] = DelayInterrupt(ob, now_ns + dtime_ms * NS_PER_MS, sign & 0xFFFF)
        return OK

    def cancel(self, ob: int) -> int:
        """SFC33 CAN_DINT: W#16#80A0 when the delay was not started."""
        if ob not in DELAY_OBS:
            return WRONG_OB
        return OK if self.pending.pop(ob, None) is not None else NOT_SET

    def status(self, ob: int) -> int:
        """SFC34 QRY_DINT STATUS without the ``loaded``/``disabled`` bits the CPU adds."""
        return ST_PENDING if ob in self.pending else 0

    def due(self, now_ns: int) -> list[DelayInterrupt]:
        """Elapsed delays (removed: each start runs its OB once)."""
        out = [d for d in self.pending.values() if d.due_ns <= now_ns]
        for d in out:
            del self.pending[d.ob]
        return out

    def clear(self) -> None:
        self.pending.clear()


@dataclass(slots=True)
class TodInterrupt:
    """One time-of-day interrupt: start, period code, activation and the next due time."""

    ob: int
    start: datetime
    period: int = Period.ONCE
    active: bool = False
    static: bool = False
    next_due: datetime | None = None


@dataclass(frozen=True, slots=True)
class TodEvent:
    """A due time-of-day interrupt; ``skipped`` when a clock jump passed over it."""

    ob: int
    due: datetime
    skipped: bool = False


class TodInterrupts:
    """OB10–OB17 on the real-time clock."""

    def __init__(self) -> None:
        self.table: dict[int, TodInterrupt] = {}

    def configure(self, ob: int, start: datetime, period: int = 0, *, active: bool = False) -> None:
        """HW-config parameters; ``active`` interrupts are (re)activated at every startup."""
        if ob not in TOD_OBS:
            raise ValueError(f"OB{ob} is not a time-of-day interrupt OB (OB10..OB17)")
        self.table[ob] = TodInterrupt(ob, start, Period(period), static=active)

    def set(self, ob: int, start: datetime, period: int) -> int:
        """SFC28 SET_TINT: new start and period, *not* active."""
        if ob not in TOD_OBS:
            return WRONG_OB
        try:
            code = Period(period)
        except ValueError:
            return WRONG_PERIOD
        self.table[ob] = TodInterrupt(ob, start, code)
        return OK

    def activate(self, ob: int, now: datetime) -> int:
        """SFC30 ACT_TINT: active from the next occurrence at or after ``now``."""
        if ob not in TOD_OBS:
            return WRONG_OB
        tod = self.table.get(ob)
        if tod is None:
            return NOT_SET
        when = next_occurrence(tod.start, tod.period, now)
        if when is None:
            return IN_THE_PAST
        tod.active, tod.next_due = True, when
        return OK

    def cancel(self, ob: int) -> int:
        """SFC29 CAN_TINT: deactivate (the start time stays set)."""
        if ob not in TOD_OBS:
            return WRONG_OB
        tod = self.table.get(ob)
        if tod is None:
            return NOT_SET
        tod.active, tod.next_due = False, None
        return OK

    def status(self, ob: int) -> int:
        """SFC31 QRY_TINT STATUS bit 2: activated and not elapsed."""
        tod = self.table.get(ob)
        return ST_PENDING if tod is not None and tod.active else 0

    def startup(self, now: datetime, *, hot: bool) -> None:
        """Warm/cold restart: program-activated interrupts become inactive (Siemens' Program Design
        for S7-300/400); HW-configured active ones are (re)activated. A hot restart keeps
        everything."""
        if hot:
            return
        for tod in self.table.values():
            tod.active, tod.next_due = False, None
            if tod.static:
                self.activate(tod.ob, now)

    def due(self, now: datetime, jumped_from: datetime | None = None) -> list[TodEvent]:
        """Active interrupts due at ``now``, in order of their due time (no state change).

        ``jumped_from`` is the clock reading before it was set forward: an occurrence in
        between is ``skipped`` — the CPU reports it to OB80 first, then runs
        it once unless OB80 cancelled it, and ``consume`` moves on past ``now``.
        """
        out: list[TodEvent] = []
        for tod in self.table.values():
            when = tod.next_due
            if not tod.active or when is None or when > now:
                continue
            out.append(TodEvent(tod.ob, when, jumped_from is not None and when > jumped_from))
        out.sort(key=lambda e: (e.due, e.ob))
        return out

    def consume(self, ob: int, now: datetime) -> bool:
        """Take the due occurrence of ``ob``: True if still active (run the OB once). A
        once-only interrupt elapses; a periodic one moves to its first occurrence after
        ``now``, so missed occurrences run once and setting the clock back repeats none."""
        tod = self.table.get(ob)
        if tod is None or not tod.active:
            return False
        after = next_occurrence(tod.start, tod.period, now + timedelta(milliseconds=1))
        if tod.period == Period.ONCE or after is None:
            tod.active, tod.next_due = False, None
        else:
            tod.next_due = after
        return True
