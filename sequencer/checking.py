"""Step 4.4 of a GRAPH FB call (docs/semantics.md, "One FB call", "Interlock" and "Supervision"):
the interlock and the supervision of active steps, with their events L1/L0 and V1/V0.

A function of a ``sequencer.cycle.GraphRuntime`` (``rt``): its ``_conditions_and_actions``
checks a sequencer's active steps before their rows, and its ``on`` a step an ``ON Sx`` row
activates while the rows of the step's own sequencer run, before that step's rows (S7-GRAPH
manual 13-14, 13-24: L1 and V1 come also at activation; manual 14-8: rows marked C run only
while the interlock holds).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Protocol

from s7graph.sequencer.state import GraphState
from s7graph.steps.qualifiers import EV_L0, EV_L1, EV_S1, EV_V0, EV_V1

if TYPE_CHECKING:
    from s7graph.sequencer.compiled import CompiledChart, Program


class _Runtime(Protocol):
    """What step 4.4 uses of ``sequencer.cycle.GraphRuntime``."""

    cc: CompiledChart
    prog: Program
    st: GraphState

    def _raise(self, i: int, bit: int) -> None: ...


def check(rt: _Runtime, steps: Iterable[int]) -> None:
    """Interlock and supervision of the active ``steps``: L1 when the interlock is lost or
    does not hold at activation (S1 in this call), L0 when it returns; V1 when a supervision
    fault comes (or is there at activation), V0 when it goes without acknowledgement
    required (or supervision is disabled). ``EN_IL = 0`` holds every interlock, ``EN_SV = 0``
    clears every fault."""
    st = rt.st
    prog = rt.prog
    ilc, svc = prog.ilc, prog.svc
    il_on = st.il_enabled
    sv_on = st.sv_enabled
    ack = st.ackreq_enabled
    ev = st.ev
    for i in steps:
        f = ilc[i]
        if f is not None:
            if il_on:
                ok, c = f(st)
            else:
                ok, c = True, 0
            st.crit_loc[i] = c
            was = st.il_ok[i] and not (ev[i] & EV_S1)
            if not ok and (was or ev[i] & EV_S1):
                rt._raise(i, EV_L1)
                st.crit_loc_err[i] = c
            elif ok and not st.il_ok[i] and not (ev[i] & EV_S1):
                rt._raise(i, EV_L0)
            st.il_ok[i] = ok
            st.il_err[i] = not ok
        f = svc[i]
        if f is not None:
            if sv_on:
                bad, c = f(st)
            else:
                bad, c = False, 0
            st.crit_sup[i] = c
            st.sv_cond[i] = bad
            if bad and not st.sv_err[i]:
                st.sv_err[i] = True
                rt._raise(i, EV_V1)
                for j in rt.cc.leaving[i]:
                    st.crit_flt[j] = st.crit[j]
            elif st.sv_err[i] and not bad and (not ack or not sv_on):
                st.sv_err[i] = False
                rt._raise(i, EV_V0)
