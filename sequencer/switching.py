"""Steps 4.1–4.3 of a general GRAPH FB call (docs/semantics.md, "One FB call" and "Decisions"): per
sequencer, evaluate the transitions leaving its active steps, decide which switch
(mode rule, HALT_SQ, supervision faults, at an alternative divergence by priority, steps held
for this call) and switch (events S0/S1 through the runtime's ``_deactivate`` and ``_activate``),
then pass through skip steps.

Functions of a ``sequencer.cycle.GraphRuntime`` (``rt``), called by its ``_sequencer``;
the fast path's switches (``sequencer.fastpath``) inline what they do in the common case.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from s7graph.sequencer.state import GraphState
from s7graph.steps.qualifiers import EV_S1

if TYPE_CHECKING:
    from s7graph.sequencer.compiled import CompiledChart, Program


class _Runtime(Protocol):
    """What switching uses of ``sequencer.cycle.GraphRuntime``."""

    cc: CompiledChart
    prog: Program
    st: GraphState
    multi: bool
    _by_seq: list[list[int]]
    passed: list[int]

    def _activate(self, i: int) -> None: ...

    def _deactivate(self, i: int) -> None: ...


def switch(
    rt: _Runtime, steps: list[int], sw: tuple[Any, ...], rule: Callable[[bool, bool], bool]
) -> None:
    """Steps a–c: evaluate, decide, switch (docs/semantics.md, "One FB call", steps 4.1–4.3) for one
    sequencer's active ``steps``. ``sw`` = (mode rule, None in AUTO; T_PUSH edge; switching blocked
    by HALT_SQ/OFF_SQ; steps whose acknowledgement forces their transition; steps ``held`` for this
    call because step 2 activated them).

    a) *every* transition whose preceding steps are all active is evaluated (``Tn.TT``, CRIT), on
    the state at the start of this step — the ones of lower priority than a switching one too;
    b) at an alternative divergence the first switchable transition in priority order wins
    (``CompiledChart.leaving``: the first written, then the lowest number). A simultaneous join
    switches only if none of its preceding steps has a switchable transition of higher priority:
    the divergence at each of its steps decides as at any other, whatever the order in which
    the steps became active;
    c) the preceding steps of every switching transition leave (S0) before the following
    steps enter (S1): a step one of them leaves and another enters stays active."""
    st = rt.st
    cc = rt.cc
    x = st.x
    leaving = cc.leaving
    tr_src = cc.tr_src
    tcond = rt.prog.tcond
    tt, crit, crit_old = st.tt, st.crit, st.crit_old
    mode_rule, push, blocked, forced, held = sw
    sv_err = st.sv_err
    # a: evaluate on the state at the start of this step; ``ok``: may switch (b, before the
    # divergences are resolved)
    ok: dict[int, bool] = {}
    for i in steps:
        for j in leaving[i]:
            srcs = tr_src[j]
            single = len(srcs) == 1
            # a simultaneous join: all preceding steps active, evaluated once
            if not single and (j in ok or not all(x[s] for s in srcs)):
                continue
            v, c = tcond[j](st)
            crit_old[j] = crit[j]
            crit[j] = c
            tt[j] = v
            if blocked or (held and not held.isdisjoint(srcs)):
                ok[j] = False
                continue
            if forced and i in forced:
                v = True
            if mode_rule is not None:
                v = mode_rule(v, push)
            if v:
                v = not sv_err[i] if single else not any(sv_err[s] for s in srcs)
            ok[j] = v
    if not any(ok.values()):
        return
    # b: at most one path per divergence, in priority order
    fire: list[int] = []
    taken: set[int] = set()
    for i in steps:
        if i in taken:
            continue
        for j in leaving[i]:
            if not ok.get(j):
                continue
            srcs = tr_src[j]
            if len(srcs) > 1 and (
                any(s in taken for s in srcs) or _outranked(j, srcs, i, leaving, tr_src, ok, taken)
            ):
                continue
            taken.update(srcs)
            fire.append(j)
            break  # alternative divergence: the first switchable path in priority order wins
    # c: switch
    if not fire:
        return
    # every preceding step leaves before any following step enters: a step one switching
    # transition leaves and another enters is active afterwards (left and entered again),
    # whatever the order of the transitions
    tr_dst = cc.tr_dst
    for j in fire:
        st.fired.append(j)
        for s in tr_src[j]:
            if x[s]:
                rt._deactivate(s)
    if st.sskip_enabled:
        first = len(st.entered)
        times = _Times(st)
        for j in fire:
            for d in tr_dst[j]:
                if not x[d]:
                    times.enter(rt, d)
        skip(rt, rule, held, first, times)
        return
    for j in fire:
        for d in tr_dst[j]:
            if not x[d]:
                rt._activate(d)


def _outranked(
    j: int,
    srcs: tuple[int, ...],
    i: int,
    leaving: tuple[tuple[int, ...], ...],
    tr_src: tuple[tuple[int, ...], ...],
    ok: dict[int, bool],
    taken: set[int],
) -> bool:
    """Whether the join ``j`` (reached from its preceding step ``i``) must give way: another of
    its preceding steps ``s`` has a switchable transition of higher priority than ``j`` whose
    own preceding steps are all still free — that path of ``s``'s divergence wins."""
    for s in srcs:
        if s == i:
            continue
        for k in leaving[s]:
            if k == j:
                break
            if ok.get(k) and not any(t in taken for t in tr_src[k]):
                return True
    return False


class _Times:
    """The step times of the steps a switch activates, as they were before (a step passed
    through keeps the time of its last activation: it never becomes active)."""

    def __init__(self, st: GraphState) -> None:
        self.st = st
        self.before: dict[int, tuple[int, int, int]] = {}

    def enter(self, rt: _Runtime, i: int) -> None:
        """Activate step ``i``, its times kept aside."""
        st = self.st
        self.before.setdefault(i, (st.t_ns[i], st.u_ns[i], st.act_ns[i]))
        rt._activate(i)

    def restore(self, i: int) -> None:
        """Give step ``i`` back the times it had before this call activated it."""
        st = self.st
        st.t_ns[i], st.u_ns[i], st.act_ns[i] = self.before[i]


def skip(
    rt: _Runtime,
    rule: Callable[[bool, bool], bool],
    held: frozenset[int],
    first: int,
    times: _Times,
) -> None:
    """Skip steps: a step this switch entered (``st.entered[first:]``) whose leaving
    transition already holds is passed through without being active (no S1, no actions;
    its ``Sn.T`` and ``Sn.U`` those of its last activation; docs/semantics.md,
    "Decisions"). A step ``held`` (activated by INIT_SQ, the first call or S_ON) or entered
    earlier in the call (by another sequencer, whose rows already ran) is never passed
    through."""
    st = rt.st
    cc = rt.cc
    for _ in range(st.n_steps):
        moved = False
        for i in st.entered[first:]:
            if not st.x[i] or i in held:
                continue
            for j in cc.leaving[i]:
                srcs = cc.tr_src[j]
                if not all(st.x[s] for s in srcs) or not held.isdisjoint(srcs):
                    continue
                v, c = rt.prog.tcond[j](st)
                st.crit_old[j], st.crit[j], st.tt[j] = st.crit[j], c, v
                if not rule(v, False):
                    continue
                for s in srcs:
                    if s in times.before and s in st.entered[first:]:  # never active
                        _pass_through(rt, s, first)
                        times.restore(s)
                    elif st.x[s]:
                        rt._deactivate(s)
                st.fired.append(j)
                for d in cc.tr_dst[j]:
                    if not st.x[d]:
                        times.enter(rt, d)
                moved = True
                break
        if not moved:
            return


def _pass_through(rt: _Runtime, s: int, first: int) -> None:
    """Take step ``s``, entered by this switch, back out as if it had never been active."""
    st = rt.st
    st.x[s] = False
    st.active.remove(s)
    if rt.multi:
        rt._by_seq[rt.cc.step_seq[s]].remove(s)
    del st.entered[first + st.entered[first:].index(s)]
    st.ev[s] &= ~EV_S1
    st.log = [e for e in st.log if e != (s, EV_S1)]
    rt.passed.append(s)  # the next call clears the satisfied bits of its transitions
