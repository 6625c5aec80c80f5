"""SFB42 CONT_S, the PI step controller for actuators with integrating behaviour (a valve
motor) without position feedback (docs/runtime.md, "Process control: CONT_C, CONT_S,
PULSEGEN"; Siemens, *System Software for S7-300/400, System and Standard Functions*, chapter
"SFB 42/FB 42 CONT_S").

One call is one sampling step of ``c = CYCLE``; PV and ER as in ``sfb.controllers``, and
``ErKp = GAIN * ER``. The motor moves the valve from stop to stop in MTR_TM, so a call with
an actuating signal moves it by ``step = 100 % * c / MTR_TM``.

- One integrator (INT), the feedback ``F``, holds the simulated valve position minus the I
  part: each call it adds the previous call's travel (``+step`` after an up signal, ``-step``
  after a down signal) and subtracts ``ErKp * c / TI``. The I part does not integrate in the
  direction of an end stop that is reached (LMNR_HS, LMNR_LS).
- The three-step element (THREE_ST) compares ``x = ErKp - F + DISV``, the travel still
  wanted, with its thresholds: a signal starts when ``|x|`` reaches the travel of a minimum
  pulse, ``100 % * max(PULSE_TM, c) / MTR_TM``, and ends when ``|x|`` falls to half a call's
  travel, ``step / 2``.
- The pulse shaper (PULSEOUT) keeps a signal on for at least PULSE_TM and, after it, both
  signals off for at least BREAK_TM (a reversal too). An end stop ends the signal towards it
  at once and refuses a new one.
- LMNS_ON: manual actuating signals: LMNUP and LMNDN (one of them alone) set the request,
  through the same pulse shaper and end stops. The integrator follows so that ``x = 0``:
  switching back to automatic sends no pulse until the error moves.
- COM_RST: every output 0, the statics to their initial values.

Choices where the manual is silent: the thresholds above (the manual's adaptation of the
response threshold, which lowers the switching frequency, is not modelled: the threshold is
fixed at a minimum pulse's travel); the feedback integration is rectangular; a new pulse may
start in the first call after COM_RST; TI and MTR_TM below CYCLE are taken as CYCLE, PULSE_TM
and BREAK_TM are counted in whole calls (a signal lasts ``ceil(PULSE_TM / CYCLE)`` calls at
least). The statics are ours: the manual does not list CONT_S's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from s7graph.sfb.controllers import (
    MS_MIN,
    Stateful,
    dead_band,
    declare,
    process_value,
)


@dataclass(frozen=True, slots=True)
class ContSIn:
    """The input pins of CONT_S with Siemens' initial values (TIME in ms, WORD as int)."""

    COM_RST: bool = False
    LMNR_HS: bool = False
    LMNR_LS: bool = False
    LMNS_ON: bool = False
    LMNUP: bool = False
    LMNDN: bool = False
    PVPER_ON: bool = False
    CYCLE: int = 1000
    SP_INT: float = 0.0
    PV_IN: float = 0.0
    PV_PER: int = 0
    GAIN: float = 2.0
    TI: int = 20_000
    DEADB_W: float = 1.0
    PV_FAC: float = 1.0
    PV_OFF: float = 0.0
    PULSE_TM: int = 3000
    BREAK_TM: int = 3000
    MTR_TM: int = 30_000
    DISV: float = 0.0


class ContSOut(NamedTuple):
    """The output pins of CONT_S."""

    QLMNUP: bool = False
    QLMNDN: bool = False
    PV: float = 0.0
    ER: float = 0.0


@dataclass(slots=True)
class ContS(Stateful):
    """SFB42 CONT_S: PI step controller; up/down signals with minimum pulse and break times
    and end stops; one call is one step of CYCLE."""

    sFbPVal: float = 0.0  # the integrator: simulated travel minus the I part, %
    sDir: int = 0  # the actuating signal on now: 1 up, -1 down, 0 none
    sPulseLeft: int = 0  # ms the signal must still stay on (PULSE_TM)
    sBreakLeft: int = 0  # ms both signals must still stay off (BREAK_TM)

    def __call__(self, p: ContSIn) -> ContSOut:
        if p.COM_RST:
            self.initialise()
            return ContSOut()
        c = max(p.CYCLE, MS_MIN)
        mtr = max(p.MTR_TM, c)
        step = 100.0 * c / mtr
        pv = process_value(p.PVPER_ON, p.PV_IN, p.PV_PER, p.PV_FAC, p.PV_OFF)
        er = dead_band(p.SP_INT - pv, p.DEADB_W)
        erkp = p.GAIN * er
        if p.LMNS_ON:
            self.sFbPVal = erkp + p.DISV
            want = int(p.LMNUP and not p.LMNDN) - int(p.LMNDN and not p.LMNUP)
        else:
            self._integrate(p, erkp, step, c)
            x = erkp - self.sFbPVal + p.DISV
            want = self._three_step(x, 100.0 * max(p.PULSE_TM, c) / mtr, step / 2)
        self._shape(p, want, c)
        return ContSOut(self.sDir > 0, self.sDir < 0, pv, er)

    def _integrate(self, p: ContSIn, erkp: float, step: float, c: int) -> None:
        """The previous call's travel in, the I part out (not towards a reached end stop)."""
        held = (erkp > 0 and p.LMNR_HS) or (erkp < 0 and p.LMNR_LS)
        self.sFbPVal += self.sDir * step - (0.0 if held else erkp * c / max(p.TI, c))

    def _three_step(self, x: float, on: float, off: float) -> int:
        """The request: a signal starts at ``|x| >= on`` and holds while ``|x| > off``."""
        if x >= on or (self.sDir > 0 and x > off):
            return 1
        if x <= -on or (self.sDir < 0 and x < -off):
            return -1
        return 0

    def _shape(self, p: ContSIn, want: int, c: int) -> None:
        """The pulse shaper: minimum pulse and break times, end stops; then count down."""
        stop = (want > 0 and p.LMNR_HS) or (want < 0 and p.LMNR_LS)
        want = 0 if stop else want
        at_stop = (self.sDir > 0 and p.LMNR_HS) or (self.sDir < 0 and p.LMNR_LS)
        if self.sDir and (at_stop or (want != self.sDir and self.sPulseLeft <= 0)):
            self.sDir, self.sPulseLeft, self.sBreakLeft = 0, 0, p.BREAK_TM
        if not self.sDir and want and self.sBreakLeft <= 0:
            self.sDir, self.sPulseLeft = want, p.PULSE_TM
        if self.sDir:
            self.sPulseLeft = max(0, self.sPulseLeft - c)
        else:
            self.sBreakLeft = max(0, self.sBreakLeft - c)


SFB42 = declare("CONT_S", ContS, ContSIn)
BLOCKS = (SFB42,)
