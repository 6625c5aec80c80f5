"""SFB41 CONT_C, the continuous PID controller (docs/runtime.md, "Process control: CONT_C,
CONT_S, PULSEGEN"; Siemens, *System Software for S7-300/400, System and Standard Functions*,
chapter "SFB 41/FB 41 CONT_C").

One call is one sampling step of ``c = CYCLE`` seconds; PV and ER as in ``sfb.controllers``,
and ``ErKp = GAIN * ER``:

- P part: ``LMN_P = ErKp`` with P_SEL, else 0.
- I part (I_SEL): trapezoidal integration, ``LMN_I += c / TI * (ErKp + ErKp') / 2`` with
  ``ErKp'`` the previous call's: after a step of the error the first call adds half of
  ``GAIN * ER * c / TI``, every later call all of it. INT_HOLD holds it, I_ITL_ON sets it to
  I_ITLVAL (before any other rule), COM_RST starts it at I_ITLVAL.
- Anti-windup: the I part does not integrate further in the direction of a limit that LMN
  reached in the previous call; and when LMN is beyond a limit with the I part itself beyond
  ``limit - DISV`` (and not by the D part alone), the I part is pulled back by the excess,
  not past ``limit - DISV``.
- D part (D_SEL, automatic mode): ``TD*s / (1 + TM_LAG*s)`` on ErKp, discretised with the
  half-cycle rule: ``LMN_D = (ErKp - r) * TD / (c/2 + TM_LAG)`` and ``r += c / TD * LMN_D``.
  A step of ErKp gives ``ErKp * TD / (c/2 + TM_LAG)`` at once, which then decays by the
  factor ``1 - c / (c/2 + TM_LAG)`` a call. Off (or in manual mode) ``r`` follows ErKp, so
  switching D on gives no kick.
- LMN: ``LMN_P + LMN_I + LMN_D + DISV``, or MAN with MAN_ON; limited to LMN_LLM..LMN_HLM
  (QLMN_HLM/QLMN_LLM say a limit is reached, ``>=``/``<=``), then ``* LMN_FAC + LMN_OFF``;
  ``LMN_PER = LMN * 27648 / 100`` as an INT in its WORD.
- Manual mode (MAN_ON) is bumpless back to automatic: the I part follows
  ``limited MAN - LMN_P - DISV`` and D is 0, so the first automatic call continues from the
  manual value.
- COM_RST: every output 0, the statics to their initial values, the I part's to I_ITLVAL.

Choices where the manual is silent: the integration rule (trapezoidal) and the anti-windup
rule above; the I part in manual mode follows this call's limited MAN (not the previous
call's LMN), so switching back is bumpless even when MAN moved in the last manual call; TI,
TD and TM_LAG below their permitted range (TI, TD >= CYCLE, TM_LAG >= CYCLE/2) are raised to
it and CYCLE below 1 ms to 1 ms; LMN_PER is rounded to the nearest INT (halves to even, as
RND) and limited to -32512..32511, the end of an analog value's overshoot range. The statics
keep the S7 instance DB's names; the sums run in double precision, and ``sRestInt`` and
``sRestDif`` carry what a sum rounded away into the next call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from s7graph.sfb.controllers import (
    MS_MIN,
    PER_FULL,
    Stateful,
    as_word,
    dead_band,
    declare,
    process_value,
    seconds,
)

PER_MIN, PER_MAX = -32512.0, 32511.0


@dataclass(frozen=True, slots=True)
class ContCIn:
    """The input pins of CONT_C with Siemens' initial values (TIME in ms, WORD as int)."""

    COM_RST: bool = False
    MAN_ON: bool = True
    PVPER_ON: bool = False
    P_SEL: bool = True
    I_SEL: bool = True
    INT_HOLD: bool = False
    I_ITL_ON: bool = False
    D_SEL: bool = False
    CYCLE: int = 1000
    SP_INT: float = 0.0
    PV_IN: float = 0.0
    PV_PER: int = 0
    MAN: float = 0.0
    GAIN: float = 2.0
    TI: int = 20_000
    TD: int = 10_000
    TM_LAG: int = 2000
    DEADB_W: float = 0.0
    LMN_HLM: float = 100.0
    LMN_LLM: float = 0.0
    PV_FAC: float = 1.0
    PV_OFF: float = 0.0
    LMN_FAC: float = 1.0
    LMN_OFF: float = 0.0
    I_ITLVAL: float = 0.0
    DISV: float = 0.0


class ContCOut(NamedTuple):
    """The output pins of CONT_C."""

    LMN: float = 0.0
    LMN_PER: int = 0
    QLMN_HLM: bool = False
    QLMN_LLM: bool = False
    LMN_P: float = 0.0
    LMN_I: float = 0.0
    LMN_D: float = 0.0
    PV: float = 0.0
    ER: float = 0.0


def lmn_per(lmn: float) -> int:
    """LMN as the I/O WORD: ``LMN * 27648 / 100`` rounded, within -32512..32511."""
    if math.isnan(lmn):  # no number: no output (the REAL itself shows it in LMN)
        return 0
    raw = min(max(lmn * PER_FULL / 100.0, PER_MIN), PER_MAX)
    return as_word(round(raw))


def _clamp(p: ContCIn, lmn: float) -> float:
    """LMN within LMN_LLM..LMN_HLM (the high limit first, should they cross)."""
    return p.LMN_HLM if lmn >= p.LMN_HLM else p.LMN_LLM if lmn <= p.LMN_LLM else lmn


@dataclass(slots=True)
class ContC(Stateful):
    """SFB41 CONT_C: PID controller with P, I and D parts, dead band, limits with anti-windup
    and bumpless manual mode; one call is one step of CYCLE."""

    sInvAlt: float = 0.0  # ErKp of the previous call (the trapezoid's other side)
    sIanteilAlt: float = 0.0  # the I part of the previous call
    sRestInt: float = 0.0  # what the I sum rounded away
    sRestDif: float = 0.0  # what the D feedback sum rounded away
    sRueck: float = 0.0  # the D part's feedback: its lag's memory
    sLmn: float = 0.0  # the limited LMN, before LMN_FAC and LMN_OFF
    sbArwHLmOn: bool = False  # LMN was at the high limit: I does not integrate upwards
    sbArwLLmOn: bool = False  # LMN was at the low limit: I does not integrate downwards
    sbILimOn: bool = True  # kept for the instance DB's layout; not read

    def __call__(self, p: ContCIn) -> ContCOut:
        if p.COM_RST:
            self.initialise()
            self.sIanteilAlt = p.I_ITLVAL
            return ContCOut()
        c = seconds(max(p.CYCLE, MS_MIN))
        pv = process_value(p.PVPER_ON, p.PV_IN, p.PV_PER, p.PV_FAC, p.PV_OFF)
        er = dead_band(p.SP_INT - pv, p.DEADB_W)
        erkp = p.GAIN * er
        lmn_p = erkp if p.P_SEL else 0.0
        lmn_d = self._derivative(p, erkp, c)
        if p.MAN_ON:
            lmn = p.MAN
            lmn_i = self._follow(p, lmn_p)
        else:
            lmn_i = self._integral(p, erkp, c)
            lmn = lmn_p + lmn_i + lmn_d + p.DISV
            lmn_i = self._unwind(p, lmn_i, lmn, lmn_d)
        self.sInvAlt, self.sIanteilAlt = erkp, lmn_i
        high, low = self._limit(p, lmn)
        out = self.sLmn * p.LMN_FAC + p.LMN_OFF
        return ContCOut(out, lmn_per(out), high, low, lmn_p, lmn_i, lmn_d, pv, er)

    def _integral(self, p: ContCIn, erkp: float, c: float) -> float:
        if not p.I_SEL or p.I_ITL_ON:
            self.sRestInt = 0.0
            return p.I_ITLVAL if p.I_SEL else 0.0
        ti = max(seconds(p.TI), c)
        diff = c / ti * (erkp + self.sInvAlt) / 2 + self.sRestInt
        if p.INT_HOLD or (diff > 0 and self.sbArwHLmOn) or (diff < 0 and self.sbArwLLmOn):
            diff = 0.0
        new = self.sIanteilAlt + diff
        self.sRestInt = self.sIanteilAlt - new + diff
        return new

    def _follow(self, p: ContCIn, lmn_p: float) -> float:
        """Manual mode: the I part that makes P + I + DISV the limited manual value."""
        self.sRestInt = 0.0
        if not p.I_SEL:
            return 0.0
        if p.I_ITL_ON:
            return p.I_ITLVAL
        return _clamp(p, p.MAN) - lmn_p - p.DISV

    @staticmethod
    def _unwind(p: ContCIn, lmn_i: float, lmn: float, lmn_d: float) -> float:
        """Anti-windup: an I part beyond ``limit - DISV`` while LMN is beyond the limit is
        pulled back by LMN's excess, not past ``limit - DISV``."""
        if not p.I_SEL or p.I_ITL_ON:
            return lmn_i
        top, bottom = p.LMN_HLM - p.DISV, p.LMN_LLM - p.DISV
        if lmn_i > top and lmn > p.LMN_HLM and lmn - lmn_d > p.LMN_HLM:
            return lmn_i - min(lmn_i - top, lmn - p.LMN_HLM)
        if lmn_i < bottom and lmn < p.LMN_LLM and lmn - lmn_d < p.LMN_LLM:
            return lmn_i - max(lmn_i - bottom, lmn - p.LMN_LLM)
        return lmn_i

    def _derivative(self, p: ContCIn, erkp: float, c: float) -> float:
        if p.MAN_ON or not p.D_SEL:
            self.sRestDif, self.sRueck = 0.0, erkp
            return 0.0
        td = max(seconds(p.TD), c)
        lag = max(seconds(p.TM_LAG), c / 2)
        lmn_d = (erkp - self.sRueck) * td / (c / 2 + lag)
        step = c / td * lmn_d + self.sRestDif
        old = self.sRueck
        self.sRueck = old + step
        self.sRestDif = old - self.sRueck + step
        return lmn_d

    def _limit(self, p: ContCIn, lmn: float) -> tuple[bool, bool]:
        """Limit LMN into ``sLmn``; the flags say which limit it reached."""
        high = lmn >= p.LMN_HLM
        low = not high and lmn <= p.LMN_LLM
        self.sLmn = _clamp(p, lmn)
        self.sbArwHLmOn, self.sbArwLLmOn = high, low
        return high, low


SFB41 = declare("CONT_C", ContC, ContCIn)
BLOCKS = (SFB41,)
