"""The fast path of one GRAPH FB call (docs/semantics.md, "One FB call"): the quiet call and step 4
in AUTO.

``FastPath`` is a part of ``sequencer.cycle.GraphRuntime`` (``GraphRuntime.fastpath``,
its ``quiet`` also the runtime's own ``quiet``): it holds references to the runtime's
tables and work lists, owns the quiet call's latch (``armed``, ``last_in``) and inlines
the general path's effects for the common case — AUTO, no HALT_SQ/OFF_SQ/skip steps,
default order — which must be the same as the general path's.
``tests/sequencer/test_fast_path_differential.py`` runs random charts through both
(``GraphRuntime(fast=False)`` forces the general path) and compares every scan. The
generated code it calls gets the runtime (``rt``), as from the general path.

Invariants the fast path relies on (every call keeps them, whichever path it takes):

* a step without interlock has ``il_ok`` True and ``il_err`` False, a step without
  supervision ``sv_err`` False (only the checks of step 4.4 write them, and only for steps
  that have the condition; activation and deactivation reset them);
* ``st.error``/``st.fault`` (set at the end of every call) say whether some active step
  has an interlock error / a supervision fault;
* a call that raises no step event changes neither the active steps nor ``il_err``/
  ``sv_err`` (activation, deactivation, an interlock lost or returned, a fault coming,
  going or acknowledged each raise one), and then leaves the per-call lists ``fired``,
  ``entered``, ``left`` and ``ev_steps`` empty like ``log``;
* ``_by_seq`` holds each sequencer's active steps in activation order: the runtime's
  ``_activate`` and ``_deactivate``, ``switching.skip`` and the switches below keep it, the
  general path rebuilds it from ``st.active`` on every call (``latch.advance``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from s7graph.sequencer.modes import MODE_RULES
from s7graph.sequencer.state import GraphState
from s7graph.steps.qualifiers import EV_S0, EV_S1

if TYPE_CHECKING:
    from s7graph.sequencer.compiled import CompiledChart, Program
    from s7graph.sequencer.display import Display

_AUTO_SW: tuple[Any, ...] = (None, False, False, (), frozenset())  # _switch options, fast path
_AUTO_RULE = MODE_RULES["AUTO"]


class Runtime(Protocol):
    """What the fast path uses of ``sequencer.cycle.GraphRuntime`` beyond its tables."""

    cc: CompiledChart
    prog: Program
    st: GraphState
    multi: bool
    display: Display
    outs_written: tuple[str, ...]
    _getter: Callable[[Any], Any]
    _permanent: bool
    _live_pins: bool
    _final: list[int]
    _late: list[int]
    _by_seq: list[list[int]]
    _done: int

    def _new_call(self, st: GraphState) -> None: ...

    def _sequencer(
        self, k: int, steps: list[int], sw: tuple[Any, ...], rule: Callable[[bool, bool], bool]
    ) -> None: ...

    def _conditions_and_actions(self, k: int, steps: list[int]) -> None: ...

    def _late_steps(self) -> None: ...


def run_rows(rt: Runtime, steps: list[int], ran: int | None) -> None:
    """The action rows of every step of ``steps`` (one sequencer's active steps, in
    activation order) but ``ran``, whose rows already ran in this call (docs/semantics.md,
    "One FB call", step 4.5: the rows of *every* active step run). A row may change
    ``steps`` while they run: an ``OFF Sx`` takes a step out — its rows do not run, it had
    its final scan, and the steps after it in the list still run theirs — and an
    ``ON Sx`` of a step of this sequencer adds it at the end, where its rows (with its
    S1) run in turn."""
    st = rt.st
    act = rt.prog.act
    ev, il_ok, x, zero = st.ev, st.il_ok, st.x, st.zeroed
    order = [i for i in steps if i != ran] if ran is not None else steps[:]
    entered = st.entered
    seen = len(entered)
    n = 0
    while n < len(order):
        i = order[n]
        n += 1
        if not x[i]:  # switched off by a row of a step before it
            continue
        act[i](st, rt, ev[i], il_ok[i], zero)
        if len(entered) != seen:  # an ON Sx row: a step of this sequencer joins the end
            for d in entered[seen:]:
                if x[d] and d != ran and d in steps and d not in order:
                    order.append(d)
            seen = len(entered)


class FastPath:
    """The quiet call and step 4 in AUTO of one ``GraphRuntime`` (``rt``)."""

    __slots__ = (
        "_by_seq",
        "_enter",
        "_final",
        "_getter",
        "_late",
        "_live_pins",
        "_nochk",
        "_permanent",
        "_plain",
        "armed",
        "cc",
        "display",
        "last_in",
        "multi",
        "prog",
        "rt",
        "seqs",
        "st",
    )

    def __init__(self, rt: Runtime) -> None:
        self.rt = rt
        cc = self.cc = rt.cc
        prog = self.prog = rt.prog
        self.st = rt.st  # the runtime's state (``GraphRuntime.rebind`` sets both)
        self.multi = rt.multi
        self.display = rt.display
        self._getter = rt._getter
        self._permanent = rt._permanent
        self._live_pins = rt._live_pins
        # the runtime's work lists (changed in place, never rebound)
        self._final = rt._final
        self._late = rt._late
        self._by_seq = rt._by_seq
        self.seqs = rt._by_seq if rt.multi else [rt.st.active]  # step 4's work lists
        # the next call is quiet if its input pins are those latched (``last_in``, the
        # input pins of the previous call) and ``armed`` (set by the general path's
        # ``_outputs``, cleared by commands, acknowledgements and ``rebind``)
        self.armed = False
        self.last_in: Any = None
        # per step: ``nochk`` = no interlock and no supervision; ``plain`` = nochk and every
        # leaving transition has this step as its only source (no join)
        self._nochk = tuple(prog.ilc[i] is None and prog.svc[i] is None for i in range(cc.n_steps))
        fused = prog.step  # per plain step: its transitions, then its rows (Program.step)
        self._plain = tuple(
            self._nochk[i]
            and all(len(cc.tr_src[j]) == 1 for j in cc.leaving[i])
            and i < len(fused)
            and fused[i] is not None
            for i in range(cc.n_steps)
        )
        # per transition: (its target, Program.enter) when it has a plain switch, else None
        enter = prog.enter or (None,) * cc.n_transitions
        self._enter = tuple(
            None if w is None else (cc.tr_dst[j][0], w) for j, w in enumerate(enter)
        )

    def quiet(self, inputs: Any, now_ns: int) -> GraphState | None:
        """The call ``execute(inputs, now_ns)`` if it is a quiet one, else None (and nothing
        done): quiet = the input pins equal those latched by the last call (no edge, no
        level change, same S_SEL) and the last call left the FB in AUTO without
        HALT_SQ/OFF_SQ/skip steps, default order, no operator command or remote
        acknowledgement queued, the display clean (``armed``, cleared by ``command``,
        ``acknowledge`` and ``rebind``).

        What it leaves out, and why that is equivalent: latching and edges (nothing
        changed); INIT_SQ, OFF_SQ, mode changes, MAN requests, acknowledgement and
        registration (each needs an edge or a queued command); display paging (no display
        input moved); ``_advance``'s rebuilding of ``_by_seq`` (kept in step, see the
        module docstring); clearing the per-call lists when the last call raised no event
        (they are empty); the group flags when this call raised none (unchanged); the
        disturbance test of U for every active step when no active step is disturbed
        (``st.error``/``st.fault``). Step 4 is ``sequencers``. A call an exception
        cuts short (a row calling a block that faults) makes the next one general, all its
        output pins written (``Display.cut_short``)."""
        if not self.armed:
            return None
        try:
            cur = self._getter(inputs)
        except KeyError:
            return None
        if cur != self.last_in:
            return None
        st = self.st
        rt = self.rt
        try:
            if st.rose:
                st.rose.clear()
            if st.log:
                rt._new_call(st)
            else:
                st.ov = False
            # 1. step times: T, and U unless the step is disturbed; HALT_TM freezes both
            last = st.last_ns
            st.last_ns = now_ns
            if now_ns != last and last >= 0 and not st.tm_halted:  # as _advance
                dt = now_ns - last
                t_ns, u_ns = st.t_ns, st.u_ns
                if st.error or st.fault:
                    il_err, sv_err = st.il_err, st.sv_err
                    for i in st.active:
                        t_ns[i] += dt
                        if not (il_err[i] or sv_err[i]):
                            u_ns[i] += dt
                else:
                    for i in st.active:
                        t_ns[i] += dt
                        u_ns[i] += dt
            st.calls += 1
            # 3.-5. permanent before, the sequencers, permanent after
            if self._permanent:
                self.prog.before(st, rt)
            active = st.active
            if self.multi or len(active) != 1 or self._final or not self._plain[active[0]]:
                self.sequencers(st, rt)
            else:  # sequencers() of the only sequencer, with one plain active step, inline
                i = active[0]
                j = self.prog.step[i](st, rt, st.ev[i], True, st.zeroed)
                if j >= 0 or len(active) > 1:
                    self._fused_done(rt, -1, active, i, j)
            if self._permanent:
                self.prog.after(st, rt)
            # 6. group flags (only events change them) and the display
            if st.log:
                il_err, sv_err = st.il_err, st.sv_err
                error = fault = False
                for i in active:
                    if il_err[i]:
                        error = True
                    if sv_err[i]:
                        fault = True
                st.error, st.fault = error, fault
                st.err_flt = error or fault
                rt.outs_written = self.display.update(st)
            elif self._live_pins:
                rt.outs_written = self.display.update(st)
            elif rt.outs_written:  # Display.update would write nothing
                rt.outs_written = ()
        except BaseException:  # a call cut short: the next one takes the general path
            self.armed = False
            self.display.cut_short()
            raise
        if st.repin:
            self.repinned(inputs)
        return st

    def repinned(self, inputs: Any) -> None:
        """The input pins the chart's rows wrote in this call (``GraphState.repin``) into
        the instance DB's ``inputs``, as S7 keeps them there; the next call latches them."""
        st = self.st
        for name in st.repin:
            inputs[name] = st.inputs[name]
        st.repin.clear()
        self.last_in = None

    def sequencers(self, st: GraphState, rt: Runtime) -> None:
        """Step 4 in the common case (AUTO, no HALT_SQ/OFF_SQ, no forced acknowledgement,
        no skip steps, default order): per sequencer, the same effects as ``_sequencer``.
        A sequencer whose only active step ``i`` has no interlock, supervision or join,
        with no final scan pending, runs the fused function ``Program.step[i]``: its
        transitions in priority order, then (none holding) its rows; the rest is
        ``_fused_done``. Any other sequencer takes the runtime's ``_sequencer``."""
        fused = self.prog.step
        plain = self._plain
        final = self._final
        ev = st.ev
        zero = st.zeroed
        multi = self.multi
        for k, steps in enumerate(self.seqs):
            rt._done = k
            # a step an earlier sequencer activated in this call is held: ``_sequencer``
            if len(steps) == 1 and plain[i := steps[0]] and not final and not ev[i] & EV_S1:
                j = fused[i](st, rt, ev[i], True, zero)
                if j >= 0 or len(steps) > 1:
                    self._fused_done(rt, k if multi else -1, steps, i, j)
            elif steps or final or not multi:
                rt._sequencer(k if multi else -1, steps, _AUTO_SW, _AUTO_RULE)
        if self._late:
            rt._late_steps()

    def _fused_done(self, rt: Runtime, kk: int, steps: list[int], i: int, j: int) -> None:
        """After the fused function of step ``i``, the only active step of sequencer ``kk``
        (-1: the only one) whose active steps are ``steps``, returned ``j``: transition
        ``j`` holds (``j`` >= 0) — the switch — or ``i``'s rows ran and appended steps to
        ``steps`` (an ON Sx row), whose rows follow in order as in ``_conditions_and_actions``.

        When ``j`` has a plain switch (``Program.enter[j]``: one target ``d`` of the same
        sequencer without interlock or supervision) it is done here — S0 of ``i``, S1 of
        ``d``, then the final scan of ``i`` and the rows of ``d`` in one generated call —
        leaving out what ``_deactivate``/``_activate`` and step e) do for nothing then:
        ``il_err``/``il_ok``/``sv_err`` of ``i`` and ``d`` already hold the values they
        write (module docstring), ``d`` is not in an earlier sequencer (no late step),
        ``_final`` is empty before and after. Any other switch is ``_switch``."""
        st = self.st
        ev = st.ev
        zero = st.zeroed
        ran = i  # the step whose rows ran: i, or after a plain switch its target d
        if j >= 0:
            plan = self._enter[j]
            if plan is None:
                self._switch(rt, kk, steps, i, j, self.multi)
                return
            d, rows = plan
            ran = d
            # c) _deactivate(i), _activate(d), inline
            x = st.x
            st.fired.append(j)
            x[i] = False
            if self.multi:
                active = st.active
                active.remove(i)
                active.append(d)
            steps[0] = d  # a single sequencer's ``steps`` is ``st.active``
            st.left.append(i)
            log = st.log
            e = ev[i]
            if not e:
                st.ev_steps.append(i)
            ev[i] = e | EV_S0
            log.append((i, EV_S0))
            x[d] = True
            st.t_ns[d] = 0
            st.u_ns[d] = 0
            st.act_ns[d] = st.last_ns
            st.entered.append(d)
            e = ev[d]
            if not e:
                st.ev_steps.append(d)
            ev[d] = e = e | EV_S1
            log.append((d, EV_S1))
            # e) the final scan of i, then the rows of d
            rows(st, rt, ev[i], e, zero)
        if len(steps) > 1:  # steps an ON Sx row appended: their rows, in order
            run_rows(rt, steps, ran)

    def _switch(self, rt: Runtime, kk: int, steps: list[int], i: int, j: int, multi: bool) -> None:
        """The fast path's switch of sequencer ``kk`` (-1: the only one) whose only active
        step ``i`` (plain, no fault) leaves by transition ``j`` (its fused function returned
        ``j``) without a plain switch: c) deactivate ``i``, activate the targets (events S0,
        S1), then d) the general path if a new step has an interlock or supervision, else
        e) the final scan of ``i`` and the rows of the new steps."""
        st = self.st
        prog = self.prog
        final = self._final
        ev = st.ev
        il_ok = st.il_ok
        sv_err = st.sv_err
        x = st.x
        il_err = st.il_err
        log = st.log
        ev_steps = st.ev_steps
        active = st.active
        st.fired.append(j)
        # _deactivate(i), inline (i is active, without fault)
        x[i] = False
        active.remove(i)
        if multi:
            steps.remove(i)
        st.left.append(i)
        final.append(i)
        il_err[i] = False
        il_ok[i] = True
        if not ev[i]:
            ev_steps.append(i)
        ev[i] |= EV_S0
        log.append((i, EV_S0))
        for d in self.cc.tr_dst[j]:
            if not x[d]:
                # _activate(d), inline
                x[d] = True
                st.t_ns[d] = 0
                st.u_ns[d] = 0
                st.act_ns[d] = st.last_ns
                il_err[d] = False
                sv_err[d] = False
                active.append(d)
                if multi:
                    k = self.cc.step_seq[d]
                    self._by_seq[k].append(d)
                    if k < rt._done:  # a jump into an earlier sequencer (_late_steps)
                        self._late.append(d)
                st.entered.append(d)
                if not ev[d]:
                    ev_steps.append(d)
                ev[d] |= EV_S1
                log.append((d, EV_S1))
        nochk = self._nochk
        if not (nochk[steps[0]] if len(steps) == 1 else all(nochk[s] for s in steps)):
            # d: a new step has an interlock or a supervision
            rt._conditions_and_actions(kk, steps)
            return
        # e: the final scan of the step left (this sequencer's), then the rows
        keep: list[int] = []
        fin = prog.fin
        step_seq = self.cc.step_seq
        for f in final:
            if kk >= 0 and step_seq[f] != kk:
                keep.append(f)
            else:
                fin[f](st, rt, ev[f] | EV_S0)
        final[:] = keep
        run_rows(rt, steps, None)  # an OFF Sx or ON Sx row may change ``steps`` meanwhile
