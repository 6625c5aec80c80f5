"""Step 1 of a general GRAPH FB call (docs/semantics.md, "One FB call" and "Decisions"): the input
pins latched with their rising edges and level options when one changed (``latch``), the step times
advanced — T; U unless the step is disturbed; HALT_TM freezes both — and each sequencer's active
steps listed again (``advance``).

Functions of a ``sequencer.cycle.GraphRuntime`` (``rt``), called by its ``_general``; the
quiet call (``sequencer.fastpath``) advances the times itself and latches nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from s7graph.sequencer.state import GraphState

if TYPE_CHECKING:
    from s7graph.sequencer.compiled import CompiledChart


class _Runtime(Protocol):
    """What step 1 uses of ``sequencer.cycle.GraphRuntime``."""

    cc: CompiledChart
    st: GraphState
    multi: bool
    input_names: tuple[str, ...]
    edge_names: tuple[str, ...]
    levels: dict[str, bool]
    _by_seq: list[list[int]]


def advance(rt: _Runtime, now_ns: int) -> None:
    """The active steps by sequencer, and the step times (T; U unless disturbed; HALT_TM
    freezes both), in one pass over the active steps."""
    st = rt.st
    last = st.last_ns
    dt = now_ns - last if last >= 0 else 0
    st.last_ns = now_ns
    active = st.active
    if dt and not st.tm_halted:
        t_ns, u_ns, il_err, sv_err = st.t_ns, st.u_ns, st.il_err, st.sv_err
        if rt.multi:
            by_seq = rt._by_seq
            for lst in by_seq:
                if lst:
                    lst.clear()
            step_seq = rt.cc.step_seq
            for i in active:
                by_seq[step_seq[i]].append(i)
                t_ns[i] += dt
                if not (il_err[i] or sv_err[i]):
                    u_ns[i] += dt
        else:
            for i in active:
                t_ns[i] += dt
                if not (il_err[i] or sv_err[i]):
                    u_ns[i] += dt
    elif rt.multi:
        by_seq = rt._by_seq
        for lst in by_seq:
            if lst:
                lst.clear()
        step_seq = rt.cc.step_seq
        for i in active:
            by_seq[step_seq[i]].append(i)


def latch(rt: _Runtime, inputs: dict[str, Any]) -> None:
    """Step 1 when an input changed: latch, detect rising edges, level options."""
    st = rt.st
    ins = st.inputs
    for name in rt.input_names:
        if name in inputs:
            ins[name] = inputs[name]
    rose = st.rose
    prev = st.prev
    for name in rt.edge_names:
        v = bool(ins[name])
        if v and not prev.get(name, False):
            rose.add(name)
        prev[name] = v
    st.off = bool(ins["OFF_SQ"])
    st.halted = bool(ins["HALT_SQ"])
    st.tm_halted = bool(ins["HALT_TM"])
    st.zeroed = bool(ins["ZERO_OP"])
    st.il_enabled = bool(ins["EN_IL"])
    st.sv_enabled = bool(ins["EN_SV"])
    if rt.levels:
        levels = rt.levels
        st.halted = levels.get("HALT_SQ", st.halted)
        st.il_enabled = levels.get("EN_IL", st.il_enabled)
        st.sv_enabled = levels.get("EN_SV", st.sv_enabled)
    st.ackreq_enabled = bool(ins["EN_ACKREQ"])
    st.sskip_enabled = bool(ins["EN_SSKIP"])
