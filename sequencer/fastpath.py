"""The fast path of one GRAPH FB call (SPEC §2.2): the quiet call and step 4 in AUTO.

``FastPath`` is a mixin of ``sequencer.cycle.GraphRuntime``: its methods are the runtime's
own (no extra call per step), kept here because they inline the general path's effects
for the common case — AUTO, no HALT_SQ/OFF_SQ/skip steps, default order — and must have
the same effects as it. ``tests/sequencer/test_fast_path_differential.py`` runs random
charts through both (``GraphRuntime(fast=False)`` forces the general path) and compares
every scan.

Invariants the fast path relies on (every call keeps them, whichever path it takes):

* a step without interlock has ``il_ok`` True and ``il_err`` False, a step without
  supervision ``sv_err`` False (only the checks of step 4d write them, and only for steps
  that have the condition; activation and deactivation reset them);
* ``st.error``/``st.fault`` (set at the end of every call) say whether some active step
  has an interlock error / a supervision fault;
* a call that raises no step event changes neither the active steps nor ``il_err``/
  ``sv_err`` (activation, deactivation, an interlock lost or returned, a fault coming,
  going or acknowledged each raise one), and then leaves the per-call lists ``fired``,
  ``entered``, ``left`` and ``ev_steps`` empty like ``log``;
* ``_by_seq`` holds each sequencer's active steps in activation order: ``_activate``,
  ``_deactivate``, ``_skip`` and the switches below keep it, the general path rebuilds it
  from ``st.active`` on every call.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from s7graph.sequencer.modes import MODE_RULES
from s7graph.sequencer.state import GraphState
from s7graph.steps.qualifiers import EV_S0, EV_S1

if TYPE_CHECKING:
    from s7graph.sequencer.compiled import CompiledChart, Program
    from s7graph.sequencer.display import Display

_AUTO_SW: tuple[Any, ...] = (None, False, False, (), frozenset())  # _switch options, fast path
_AUTO_RULE = MODE_RULES["AUTO"]


class FastPath:
    """The fast-path methods of ``GraphRuntime`` (which defines the attributes below)."""

    if TYPE_CHECKING:
        cc: CompiledChart
        prog: Program
        st: GraphState
        multi: bool
        display: Display
        outs_written: tuple[str, ...]
        _quiet: bool
        _getter: Callable[[Any], Any]
        _last_in: Any
        _seqs: list[list[int]]
        _by_seq: list[list[int]]
        _done: int
        _late: list[int]
        _final: list[int]
        _permanent: bool
        _plain: tuple[bool, ...]
        _nochk: tuple[bool, ...]
        _enter: tuple[tuple[int, Any] | None, ...]
        _live_pins: bool
        _new_call: Callable[[GraphState], None]
        _sequencer: Callable[[int, list[int], tuple[Any, ...], Callable[[bool, bool], bool]], None]
        _conditions_and_actions: Callable[[int, list[int]], None]
        _late_steps: Callable[[], None]

    def quiet(self, inputs: Any, now_ns: int) -> GraphState | None:
        """The call ``execute(inputs, now_ns)`` if it is a quiet one, else None (and nothing
        done): quiet = the input pins equal those latched by the last call (no edge, no
        level change, same S_SEL) and the last call left the FB in AUTO without
        HALT_SQ/OFF_SQ/skip steps, default order, no operator command or remote
        acknowledgement queued, the display clean (``_quiet``, cleared by ``command``,
        ``acknowledge`` and ``rebind``).

        What it leaves out, and why that is equivalent: latching and edges (nothing
        changed); INIT_SQ, OFF_SQ, mode changes, MAN requests, acknowledgement and
        registration (each needs an edge or a queued command); display paging (no display
        input moved); ``_advance``'s rebuilding of ``_by_seq`` (kept in step, see the
        module docstring); clearing the per-call lists when the last call raised no event
        (they are empty); the group flags when this call raised none (unchanged); the
        disturbance test of U for every active step when no active step is disturbed
        (``st.error``/``st.fault``). Step 4 is ``_fast_sequencers``. A call an exception
        cuts short (a row calling a block that faults) makes the next one general, all its
        output pins written (``Display.cut_short``)."""
        if not self._quiet:
            return None
        try:
            cur = self._getter(inputs)
        except KeyError:
            return None
        if cur != self._last_in:
            return None
        st = self.st
        try:
            if st.rose:
                st.rose.clear()
            if st.log:
                self._new_call(st)
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
                self.prog.before(st, self)
            active = st.active
            if self.multi or len(active) != 1 or self._final or not self._plain[active[0]]:
                self._fast_sequencers(st)
            else:  # _fast_sequencers of the only sequencer, with one plain active step, inline
                i = active[0]
                j = self.prog.step[i](st, self, st.ev[i], True, st.zeroed)
                if j >= 0 or len(active) > 1:
                    self._fused_done(-1, active, i, j)
            if self._permanent:
                self.prog.after(st, self)
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
                self.outs_written = self.display.update(st)
            elif self._live_pins:
                self.outs_written = self.display.update(st)
            elif self.outs_written:  # Display.update would write nothing
                self.outs_written = ()
        except BaseException:  # a call cut short: the next one takes the general path
            self._quiet = False
            self.display.cut_short()
            raise
        return st

    def _fast_sequencers(self, st: GraphState) -> None:
        """Step 4 in the common case (AUTO, no HALT_SQ/OFF_SQ, no forced acknowledgement,
        no skip steps, default order): per sequencer, the same effects as ``_sequencer``.
        A sequencer whose only active step ``i`` has no interlock, supervision or join,
        with no final scan pending, runs the fused function ``Program.step[i]``: its
        transitions in priority order, then (none holding) its rows; the rest is
        ``_fused_done``. Any other sequencer takes ``_sequencer``."""
        fused = self.prog.step
        plain = self._plain
        final = self._final
        ev = st.ev
        zero = st.zeroed
        multi = self.multi
        for k, steps in enumerate(self._seqs):
            self._done = k
            if len(steps) == 1 and plain[i := steps[0]] and not final:
                j = fused[i](st, self, ev[i], True, zero)
                if j >= 0 or len(steps) > 1:
                    self._fused_done(k if multi else -1, steps, i, j)
            elif steps or final or not multi:
                self._sequencer(k if multi else -1, steps, _AUTO_SW, _AUTO_RULE)
        if self._late:
            self._late_steps()

    def _fused_done(self, kk: int, steps: list[int], i: int, j: int) -> None:
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
        ``_final`` is empty before and after. Any other switch is ``_fast_switch``."""
        st = self.st
        ev = st.ev
        zero = st.zeroed
        if j >= 0:
            plan = self._enter[j]
            if plan is None:
                self._fast_switch(kk, steps, i, j, self.multi)
                return
            d, rows = plan
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
            rows(st, self, ev[i], e, zero)
        if len(steps) > 1:  # steps an ON Sx row appended: their rows, in order
            act, il_ok = self.prog.act, st.il_ok
            n = 1
            while n < len(steps):
                i = steps[n]
                n += 1
                act[i](st, self, ev[i], il_ok[i], zero)

    def _fast_switch(self, kk: int, steps: list[int], i: int, j: int, multi: bool) -> None:
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
        zero = st.zeroed
        act = prog.act
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
                    if k < self._done:  # a jump into an earlier sequencer (_late_steps)
                        self._late.append(d)
                st.entered.append(d)
                if not ev[d]:
                    ev_steps.append(d)
                ev[d] |= EV_S1
                log.append((d, EV_S1))
        nochk = self._nochk
        if not (nochk[steps[0]] if len(steps) == 1 else all(nochk[s] for s in steps)):
            # d: a new step has an interlock or a supervision
            self._conditions_and_actions(kk, steps)
            return
        # e: the final scan of the step left (this sequencer's), then the rows
        keep: list[int] = []
        fin = prog.fin
        step_seq = self.cc.step_seq
        for f in final:
            if kk >= 0 and step_seq[f] != kk:
                keep.append(f)
            else:
                fin[f](st, self, ev[f] | EV_S0)
        final[:] = keep
        n = 0
        while n < len(steps):  # ON Sx in a row may append a step to this sequencer
            i = steps[n]
            n += 1
            act[i](st, self, ev[i], il_ok[i], zero)
