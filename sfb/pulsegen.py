"""SFB43 PULSEGEN, the pulse generator: pulse-width modulation of a manipulated value for
two-step and three-step controllers (docs/runtime.md, "Process control: CONT_C, CONT_S,
PULSEGEN"; Siemens, *System Software for S7-300/400, System and Standard Functions*, chapter
"SFB 43/FB 43 PULSEGEN").

A period PER_TM is ``n = PER_TM / CYCLE`` calls (rounded, at least 1). At the first call of a
period INV is sampled into a pulse duration, and the output is on for the first
``duration / CYCLE`` calls (rounded) of the period: INV = 30 % with 10 calls a period gives
3 calls on, 7 off.

- Three-step (STEP3_ON): INV > 0 pulses QPOS_P for ``INV / 100 * PER_TM``, INV < 0 pulses
  QNEG_P for ``-INV / 100 * PER_TM``. RATIOFAC < 1 multiplies the negative duration by it,
  RATIOFAC > 1 divides the positive one by it.
- Two-step (STEP3_ON = FALSE): QPOS_P pulses, QNEG_P is its negation. Bipolar (ST2BI_ON),
  INV -100..100 % is 0..100 % of the period: ``(INV + 100) / 200 * PER_TM``; unipolar, INV
  0..100 %: ``INV / 100 * PER_TM``.
- Minimum pulse/break P_B_TM: a duration below P_B_TM gives no pulse, one above
  ``PER_TM - P_B_TM`` a pulse over the whole period.
- Synchronisation (SYN_ON): when INV changes in a call that is not one of the first two or
  the last two of the period, a new period starts with that call, so the new value is output
  at once.
- Manual mode (MAN_ON): three-step, QPOS_P = POS_P_ON and QNEG_P = NEG_P_ON, both off when
  both are on; two-step, QPOS_P = POS_P_ON and QNEG_P its negation. Back in automatic mode a
  new period starts.
- COM_RST: both outputs 0, a new period starts.

Choices where the manual is silent: the call counts are rounded to the nearest (halves up);
"not in the first or last two call cycles" is read as neither of the first two nor of the
last two; RATIOFAC outside 0.1..10 (the permitted range) is taken as the nearer bound; a
duration is limited to 0..PER_TM before P_B_TM applies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from s7graph.sfb.controllers import MS_MIN, Stateful, declare


@dataclass(frozen=True, slots=True)
class PulseGenIn:
    """The input pins of PULSEGEN with Siemens' initial values (TIME in ms)."""

    INV: float = 0.0
    PER_TM: int = 1000
    P_B_TM: int = 50
    RATIOFAC: float = 1.0
    STEP3_ON: bool = True
    ST2BI_ON: bool = False
    MAN_ON: bool = False
    POS_P_ON: bool = False
    NEG_P_ON: bool = False
    SYN_ON: bool = True
    COM_RST: bool = False
    CYCLE: int = 10


class PulseGenOut(NamedTuple):
    """The output pins of PULSEGEN."""

    QPOS_P: bool = False
    QNEG_P: bool = False


def _calls(ms: float, cycle: int) -> int:
    """A duration in whole calls, rounded to the nearest (halves up); a duration that is
    not a number (a NaN INV) none, an infinite one the longest a DINT counts."""
    calls = ms / cycle + 0.5
    if not math.isfinite(calls):
        return 2**31 - 1 if calls > 0 else 0
    return math.floor(calls)


def durations(p: PulseGenIn) -> tuple[float, float]:
    """The positive and negative pulse durations (ms) for INV, after RATIOFAC and P_B_TM."""
    per = max(p.PER_TM, 0)
    if p.STEP3_ON:
        ratio = min(max(p.RATIOFAC, 0.1), 10.0)
        pos = max(p.INV, 0.0) / 100.0 * per
        neg = max(-p.INV, 0.0) / 100.0 * per
        if ratio < 1:
            neg *= ratio
        elif ratio > 1:
            pos /= ratio
    else:
        pos = ((p.INV + 100.0) / 200.0 if p.ST2BI_ON else p.INV / 100.0) * per
        neg = 0.0
    return _min_pulse(pos, per, p.P_B_TM), _min_pulse(neg, per, p.P_B_TM)


def _min_pulse(ms: float, per: int, p_b_tm: int) -> float:
    """Below P_B_TM: no pulse; above PER_TM - P_B_TM: the whole period."""
    ms = min(max(ms, 0.0), float(per))
    if ms < p_b_tm:
        return 0.0
    return float(per) if ms > per - p_b_tm else ms


@dataclass(slots=True)
class PulseGen(Stateful):
    """SFB43 PULSEGEN: INV as pulses of constant period PER_TM, three-step or two-step, with
    minimum pulse/break time, ratio factor, synchronisation and manual mode."""

    sCount: int = 0  # this call's place in the period, 0..n-1
    sPosCalls: int = 0  # calls QPOS_P is on in this period
    sNegCalls: int = 0  # calls QNEG_P is on in this period (three-step)
    sInvAlt: float = 0.0  # INV of the previous call

    def __call__(self, p: PulseGenIn) -> PulseGenOut:
        if p.COM_RST:
            self.initialise()
            return PulseGenOut()
        if p.MAN_ON:
            self.sCount, self.sInvAlt = 0, p.INV
            if p.STEP3_ON:
                return PulseGenOut(p.POS_P_ON and not p.NEG_P_ON, p.NEG_P_ON and not p.POS_P_ON)
            return PulseGenOut(p.POS_P_ON, not p.POS_P_ON)
        c = max(p.CYCLE, MS_MIN)
        n = max(1, _calls(p.PER_TM, c))
        k = self.sCount if self.sCount < n else 0
        if k == 0 or (p.SYN_ON and self.sInvAlt != p.INV and 2 <= k < n - 2):
            k = 0
            pos, neg = durations(p)
            self.sPosCalls, self.sNegCalls = _calls(pos, c), _calls(neg, c)
        self.sCount, self.sInvAlt = (k + 1) % n, p.INV
        on = k < self.sPosCalls
        return PulseGenOut(on, k < self.sNegCalls if p.STEP3_ON else not on)


SFB43 = declare("PULSEGEN", PulseGen, PulseGenIn)
BLOCKS = (SFB43,)
