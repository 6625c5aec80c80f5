"""The fast path of one GRAPH FB call (SPEC §2.2): the quiet call and step 4 in AUTO.

``FastPath`` is a mixin of ``sequencer.cycle.GraphRuntime``: its methods are the runtime's
own (no extra call per step), kept here because they inline the general path's effects
for the common case — AUTO, no HALT_SQ/OFF_SQ/skip steps, default order — and must have
the same effects as it.
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
        outs_changed: bool
        _by_seq: list[list[int]]
        _done: int
        _late: list[int]
        _final: list[int]
        _acked: set[int]
        _target: int | None
        _permanent: bool
        _plain: tuple[bool, ...]
        _none: tuple[bool, ...]
        _nochk: tuple[bool, ...]
        _tcond: Any
        _act: Any
        _live_pins: bool
        _advance: Callable[[int], None]
        _new_call: Callable[[GraphState], None]
        _sequencer: Callable[[int, list[int], tuple[Any, ...], Callable[[bool, bool], bool]], None]
        _conditions_and_actions: Callable[[int, list[int]], None]
        _late_steps: Callable[[], None]

    def _quiet_call(self, st: GraphState, now_ns: int) -> GraphState:
        """The quiet call: no input pin changed since the last latch, no command or
        remote acknowledgement is queued, the display needs no paging, AUTO without
        HALT_SQ/OFF_SQ/skip steps, default order — the same effects as ``execute`` with the
        steps that cannot act then left out (latch, edges, INIT_SQ, requests,
        acknowledgement); step 4 is the fast path."""
        rose = st.rose
        if rose:
            rose.clear()
        active = st.active
        if self.multi:
            self._advance(now_ns)
        else:  # _advance, inline
            last = st.last_ns
            st.last_ns = now_ns
            if last >= 0 and now_ns != last and not st.tm_halted:
                dt = now_ns - last
                t_ns, u_ns, il_err, sv_err = st.t_ns, st.u_ns, st.il_err, st.sv_err
                for i in active:
                    t_ns[i] += dt
                    if not (il_err[i] or sv_err[i]):
                        u_ns[i] += dt
        self._target = None
        self._new_call(st)
        if self._acked:
            self._acked.clear()
        st.calls += 1
        if self._permanent:
            self.prog.before(st, self)
            self._fast_sequencers(self._by_seq if self.multi else [active], self.multi)
            self.prog.after(st, self)
        elif self.multi or len(active) != 1:
            self._fast_sequencers(self._by_seq if self.multi else [active], self.multi)
        else:  # _fast_sequencers of the only sequencer with one active step, inline
            i = active[0]
            prog = self.prog
            if (
                self._plain[i]
                and not st.sv_err[i]
                and not self._final
                and prog.tcond is self._tcond
                and prog.act is self._act
            ):
                ev = st.ev
                j = prog.step[i](st, self, ev[i], st.il_ok[i], st.zeroed)
                if j >= 0:
                    self._fast_switch(-1, active, i, j, False)
                elif len(active) > 1:  # a step an ON Sx row of step i appended
                    act, il_ok, zero = prog.act, st.il_ok, st.zeroed
                    n = 1
                    while n < len(active):
                        i = active[n]
                        n += 1
                        act[i](st, self, ev[i], il_ok[i], zero)
            else:
                self._fast_sequencers([active], False)
        # 6. _outputs, inline
        il_err, sv_err = st.il_err, st.sv_err
        error = fault = False
        for i in active:
            if il_err[i]:
                error = True
            if sv_err[i]:
                fault = True
        st.error, st.fault = error, fault
        st.err_flt = error or fault
        disp = self.display
        if disp.dirty or st.log or self._live_pins:
            self.outs_changed = True
            disp.update(st)
        else:  # Display.update would write nothing: no page, no event, no live pin
            self.outs_changed = False
        return st

    def _fast_sequencers(self, seqs: list[list[int]], multi: bool) -> None:
        """Step 4 in the common case (AUTO, no HALT_SQ/OFF_SQ, no forced acknowledgement,
        no skip steps, default order): per sequencer (``seqs``: the active steps of each, or
        ``[st.active]`` for a single one), the same effects as ``_sequencer``. Only a
        sequencer with one active step without interlock, supervision or join, and no final
        scan pending, is done here; any other takes the general path."""
        st = self.st
        prog = self.prog
        fused = prog.step
        act = prog.act
        # the fused functions embed the chart's conditions and rows: with a replaced
        # ``tcond``/``act`` (instrumented) every sequencer takes the general path
        plain = self._plain if prog.tcond is self._tcond and act is self._act else self._none
        final = self._final
        ev = st.ev
        il_ok = st.il_ok
        sv_err = st.sv_err
        zero = st.zeroed
        for k in range(len(seqs)):
            steps = seqs[k]
            kk = k if multi else -1
            self._done = k
            if len(steps) != 1 or final:
                if steps or final or not multi:
                    self._sequencer(kk, steps, _AUTO_SW, _AUTO_RULE)
                continue
            i = steps[0]
            if not plain[i] or sv_err[i]:
                self._sequencer(kk, steps, _AUTO_SW, _AUTO_RULE)
                continue
            # a–c: the first-listed transition that holds switches; if none, the rows (e)
            j = fused[i](st, self, ev[i], il_ok[i], zero)
            if j < 0:
                n = 1
                while n < len(steps):  # a step an ON Sx row of step i appended
                    i = steps[n]
                    n += 1
                    act[i](st, self, ev[i], il_ok[i], zero)
                continue
            self._fast_switch(kk, steps, i, j, multi)
        self._late_steps()

    def _fast_switch(self, kk: int, steps: list[int], i: int, j: int, multi: bool) -> None:
        """The fast path's switch of sequencer ``kk`` (-1: the only one) whose only active
        step ``i`` (plain, no fault) leaves by transition ``j`` (its fused function returned
        ``j``): c) deactivate ``i``, activate the targets (events S0, S1), then d) the
        general path if a new step has an interlock or supervision, else e) the final scan
        of ``i`` and the rows of the new steps."""
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
