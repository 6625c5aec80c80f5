"""IEC timers SFB3 TP, SFB4 TON, SFB5 TOF (docs/runtime.md, "The block runtime"; STEP7 comprehensive
guide vol. 2, ch. 12).

Each timer is a small state machine over its own instance data and ``(IN, PT, now_ns)``:
TIME is integer milliseconds with 1 ms resolution up to ``T#24D20H31M23S647MS``; time runs
on the injected clock and ``Q``/``ET`` change only when the instance is called.
The state fields mirror the instance DB (``IN PT Q ET`` plus the start time), so an instance
round-trips through ``to_state()``/``from_state()``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, NamedTuple, Self, cast

from s7graph.engine import blocks
from s7graph.sfb.catalogue import engine_sections, lookup

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

NS_PER_MS = 1_000_000
TIME_MAX_MS = 2**31 - 1  # T#24D20H31M23S647MS


class TimerOut(NamedTuple):
    """What an IEC timer call returns: output ``Q`` and elapsed time ``ET`` in ms."""

    q: bool
    et: int


def _clamp_pt(pt: int) -> int:
    """PT outside 0..T#24D20H31M23S647MS is clamped (a negative preset acts as T#0MS)."""
    return max(0, min(int(pt), TIME_MAX_MS))


def _elapsed_ms(start_ns: int, now_ns: int, pt: int) -> int:
    return min(max(0, now_ns - start_ns) // NS_PER_MS, pt)


@dataclass(slots=True)
class _IecTimer:
    """Instance data shared by TP/TON/TOF: latched inputs, outputs and the start time."""

    IN: bool = False
    PT: int = 0
    Q: bool = False
    ET: int = 0
    running: bool = False
    start_ns: int = 0
    resume: bool = field(default=False, compare=False)  # restored running: ``_rebase``

    def to_state(self) -> dict[str, object]:
        data = asdict(self)
        del data["resume"]
        return data

    @classmethod
    def from_state(cls, data: dict[str, object]) -> Self:
        obj = cls()
        obj.restore(data)
        return obj

    def restore(self, data: dict[str, object]) -> None:
        """Take ``data`` (``to_state``); a running time resumes from its ET at the next
        call, since ``start_ns`` was on the clock of the process that saved it (a hot
        restart resumes times as persisted, as a GRAPH FB's step times do)."""
        for name, value in data.items():
            if name in self.__dataclass_fields__ and name != "resume":
                setattr(self, name, value)
        self.resume = self.running

    def _rebase(self, now_ns: int) -> None:
        if self.resume:
            self.resume = False
            self.start_ns = now_ns - self.ET * NS_PER_MS

    def reset(self) -> None:
        """Cold-restart initialisation (the OS resets SFB0-5 instances only on cold restart)."""
        self.restore(type(self)().to_state())


@dataclass(slots=True)
class TP(_IecTimer):
    """SFB3 TP: a rising IN starts a pulse of length PT; not retriggerable.

    Q = 1 for PT from the rising edge regardless of IN; ET runs to PT, holds there while IN = 1
    and returns to 0 once the pulse is over and IN = 0 (STEP7 comprehensive guide vol. 2, ch. 12).
    """

    def __call__(self, IN: bool, PT: int, now_ns: int) -> TimerOut:
        self._rebase(now_ns)
        pt = _clamp_pt(PT)
        rising = IN and not self.IN
        self.IN, self.PT = bool(IN), pt
        if rising and not self.running and not self.Q:
            self.running, self.start_ns = True, now_ns
        if self.running:
            self.ET = _elapsed_ms(self.start_ns, now_ns, pt)
            if pt <= self.ET:
                self.running = False
        if not self.running and not self.IN:
            self.ET = 0
        self.Q = self.running
        return TimerOut(self.Q, self.ET)


@dataclass(slots=True)
class TON(_IecTimer):
    """SFB4 TON: Q = 1 once IN has been 1 for PT; IN = 0 resets Q and ET (STEP7 comprehensive guide
    vol. 2, ch. 12)."""

    def __call__(self, IN: bool, PT: int, now_ns: int) -> TimerOut:
        self._rebase(now_ns)
        pt = _clamp_pt(PT)
        if IN and not self.IN:
            self.start_ns = now_ns
        self.IN, self.PT = bool(IN), pt
        self.running = self.IN
        if self.IN:
            self.ET = _elapsed_ms(self.start_ns, now_ns, pt)
            self.Q = pt <= self.ET
        else:
            self.ET, self.Q = 0, False
        return TimerOut(self.Q, self.ET)


@dataclass(slots=True)
class TOF(_IecTimer):
    """SFB5 TOF: IN = 1 gives Q = 1 and ET = 0; a falling IN starts the delay, Q falls after PT.

    A rising IN during the delay resets ET to 0 and keeps Q = 1; after expiry ET holds PT while
    IN stays 0 (STEP7 comprehensive guide vol. 2, ch. 12).
    """

    def __call__(self, IN: bool, PT: int, now_ns: int) -> TimerOut:
        self._rebase(now_ns)
        pt = _clamp_pt(PT)
        falling = self.IN and not IN
        self.IN, self.PT = bool(IN), pt
        if self.IN:
            self.Q, self.ET, self.running = True, 0, False
        else:
            if falling:
                self.running, self.start_ns = True, now_ns
            if self.running:
                self.ET = _elapsed_ms(self.start_ns, now_ns, pt)
                if pt <= self.ET:
                    self.running, self.Q = False, False
        return TimerOut(self.Q, self.ET)


# --- Engine adapter: SFB3/4/5 as engine SFBs (instance DB: IN PT Q ET + STATE) -----------


def _declare(cls: type[TP] | type[TON] | type[TOF]) -> blocks.FB:
    entry = lookup(cls.__name__)
    sections, _ = engine_sections(entry)

    def body(ctx: CallContext, idb: blocks.InstanceDB) -> None:
        state = idb.values["STATE"]
        assert isinstance(state, cls)
        v = idb.values
        v["Q"], v["ET"] = state(v["IN"] is True, cast(int, v["PT"]), ctx.now_ns)

    body.__doc__ = f"{entry.key} {entry.name}: {cls.__doc__}"
    stat = {"STATE": (blocks.OBJECT, cls)}
    return blocks.sfb(entry.number, entry.name, STAT=stat, **sections)(body)


SFB3 = _declare(TP)
SFB4 = _declare(TON)
SFB5 = _declare(TOF)
BLOCKS = (SFB3, SFB4, SFB5)
