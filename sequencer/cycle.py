"""One call of a GRAPH FB: the algorithm of docs/semantics.md, "One FB call", in that order
(docs/semantics.md, "Decisions").

1. latch the FB inputs, detect rising edges, advance step times (T; U unless disturbed;
   both frozen by HALT_TM);
2. apply OFF_SQ, INIT_SQ (and the very first call, which initializes like INIT_SQ), mode
   changes, MAN requests S_ON/S_OFF and placements (``sequencer.placing``), acknowledgement
   (ACK_EF, ACK_S) and registration;
3. permanent *before* instructions;
4. per sequencer, in definition order: a) evaluate the transitions leaving active steps
   (criteria bits), b) decide which switch (mode rule, HALT_SQ, supervision faults, at an
   alternative divergence the first written, then the lowest number; a step activated in
   step 2 — INIT_SQ, the first call, S_ON — stays for this call, STEP7 comprehensive guide
   vol. 2, ch. 14), c) switch (S0/S1, skip steps), d) interlock and supervision of the
   active steps, e) final scans of the steps left, then the action rows of the active
   steps; then d) and e) of the steps a
   later sequencer activated in an earlier one (``_late_steps``: every activation runs
   its S1 rows, S7-GRAPH manual 6-2, 6-4);
5. permanent *after* instructions;
6. group flags and FB outputs.

The quiet call and the fast path of step 4 are ``sequencer/fastpath.py``'s ``FastPath``, a part of
the runtime (``GraphRuntime.fastpath``); steps 4.1–4.3 of the general path (evaluate, decide,
switch, skip steps) are ``sequencer/switching.py``. The option ``order = "codesys"`` runs d) and e)
before a)–c): new steps act in the next call (their S1 rows once: a step whose rows ran in its
activation call is not carried). Work is proportional to the active steps: only ``st.active`` is
visited.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Iterable
from typing import Any

from s7graph.engine.blocks import from_stored
from s7graph.sequencer import display
from s7graph.sequencer.checking import check
from s7graph.sequencer.compiled import CompiledChart, Program
from s7graph.sequencer.fastpath import FastPath, run_rows
from s7graph.sequencer.latch import advance, latch
from s7graph.sequencer.modes import MODE_RULES, select_mode
from s7graph.sequencer.params import input_defaults, inputs_for, output_defaults
from s7graph.sequencer.placing import place
from s7graph.sequencer.state import EDGE_INPUTS, GraphState
from s7graph.sequencer.switching import switch
from s7graph.steps.qualifiers import EV_A1, EV_R1, EV_S0, EV_S1, EV_V0

BlockCaller = Callable[[str, Any, Any, dict[str, Any]], dict[str, Any]]
CellOp = Callable[[str, int, Any], None]


def _no_calls(kind: str, block: Any, instance: Any, params: dict[str, Any]) -> dict[str, Any]:
    raise RuntimeError(f"CALL {kind} {block}: no block runtime bound to this sequencer")


def _no_cells(op: str, number: int, value: Any) -> None:
    raise RuntimeError(f"{op} {number}: no timer/counter cells bound to this sequencer")


class GraphRuntime:
    """A compiled chart bound to its state and the engine: ``execute`` is one FB call.

    Generated action code calls back ``on``/``off``/``off_all`` (ON/OFF Sx, OFF S_ALL),
    ``call`` (CALL of a block) and ``counter``/``timer`` (CS CU CD CR / TL TD TF TR).
    ``quiet`` is the quiet call of its ``fastpath`` (``FastPath.quiet``)."""

    def __init__(
        self,
        cc: CompiledChart,
        prog: Program,
        state: GraphState | None = None,
        *,
        call: BlockCaller = _no_calls,
        counter: CellOp = _no_cells,
        timer: CellOp = _no_cells,
        fast: bool = True,
    ) -> None:
        self.cc = cc
        # False forces the general path on every call (the differential test compares both)
        self.fast = fast
        self.prog = prog
        self.st = dated(cc, state) if state is not None else new_state(cc)
        self._call = call
        self.counter = counter
        self.timer = timer
        params = cc.parameters
        self.input_names = tuple(p.name for p in inputs_for(params))
        self.edge_names = tuple(n for n in self.input_names if n in EDGE_INPUTS)
        self.codesys = cc.options.order == "codesys"
        self.multi = len(cc.seq_numbers) > 1
        self._acked: set[int] = set()  # steps acknowledged in this call
        self._remote: list[int] = []  # acknowledgements queued for the next call
        self._commands: list[tuple[str, int | None]] = []  # operator commands, next call
        self._target: int | None = None  # step of this call's S_ON/S_OFF/ACK_S command
        self.placing: tuple[int, ...] = ()  # steps to place in the next call (MAN)
        self.entering: tuple[int, ...] = ()  # steps made active outside a call: S1 next call
        self.levels = self.st.levels  # overrides of HALT_SQ / EN_IL / EN_SV (kept in the state)
        self._final: list[int] = []  # steps left, awaiting their final scan
        self._getter: Callable[[Any], Any] = operator.itemgetter(*self.input_names)
        self.display = display.Display(cc)
        self._permanent = bool(cc.chart.before or cc.chart.after)
        # per sequencer: its active steps in activation order (multi-sequencer FBs only),
        # rebuilt from ``st.active`` by each general call (latch.advance) and kept in step
        # by _activate/_deactivate, switching.skip and the fast path's switches
        self._by_seq: list[list[int]] = [[] for _ in cc.seq_numbers] if self.multi else []
        # step 4: the sequencers before ``_done`` have run their rows in this call; a step
        # activated in one of them waits in ``_late`` (see _late_steps); with the CODESYS
        # order such steps are carried to the next call (``_carry``: S1 raised again there)
        self._done = 0
        self._late: list[int] = []
        self._carry: list[int] = []
        self.passed: list[int] = []
        """The steps skip steps passed through in the last call (``switching.skip``)."""
        self._forcing = cc.options.ack_forces_switch
        self._lean = fast and not self.codesys  # a call may be quiet (FastPath.quiet)
        self._live_pins = bool(self.display.plan.live_pins)
        # the pins of st.outputs the last call wrote (GraphFB copies them)
        self.outs_written: tuple[str, ...] = ()
        # the quiet call and the fast path of step 4 (AUTO, no HALT/OFF, no skip steps,
        # default order); its quiet call is this runtime's own, one lookup from OB1
        self.fastpath = FastPath(self)
        self.quiet = self.fastpath.quiet

    def rebind(self, state: GraphState) -> None:
        """Run on another instance-DB content (restored snapshot, new instance)."""
        self.st = state = dated(self.cc, state)
        fp = self.fastpath
        fp.st = state
        fp.armed = False
        if not self.multi:
            fp.seqs = [state.active]
        self.levels = state.levels
        self._final.clear()
        self._acked.clear()
        fp.last_in = None
        self._remote.clear()
        self._commands.clear()
        self.placing = ()
        self.entering = ()
        self._late.clear()
        self._carry.clear()
        self._done = 0
        self.display.dirty = True

    # ------------------------------------------------------------ callbacks of generated code

    def call(self, kind: str, block: Any, instance: Any, params: dict[str, Any]) -> dict[str, Any]:
        return self._call(kind, block, instance, params)

    def on(self, i: int) -> None:
        """ON Sx: activate step ``i`` now (event S1); its rows run in this call. A step of the
        sequencer whose rows run (its step 4.4 done) has its interlock and supervision
        checked at once, before its rows (L1/V1 at activation, rows marked C held back)."""
        if not self.st.x[i]:
            self._activate(i)
            if self.cc.step_seq[i] == self._done:
                check(self, (i,))

    def off(self, i: int) -> None:
        """OFF Sx: deactivate step ``i`` now (event S0) and run its final scan."""
        st = self.st
        if st.x[i]:
            self._deactivate(i)
            self._final.remove(i)
            self.prog.fin[i](st, self, st.ev[i])

    def off_all(self, keep: int) -> None:
        """OFF S_ALL: deactivate every step except ``keep`` (the one holding the action)."""
        for i in list(self.st.active):
            if i != keep:
                self.off(i)

    def acknowledge(self, step_indices: Iterable[int]) -> None:
        """Queue acknowledgements of steps' supervision faults from outside the FB (a user
        acknowledging the message, docs/semantics.md, "Messages"): the next call releases each step
        still latched exactly as ACK_S does (events A1, V0; the step may switch in that call)."""
        self._remote.extend(step_indices)
        self.fastpath.armed = False

    def command(self, pin: str, step: int | None = None) -> None:
        """Queue an operator command (S7-GRAPH "Control Sequencer", docs/semantics.md, "Modes" and
        "FB pins"): ``pin`` acts in the next call as a one-call rising edge whatever the parameter
        set and the pin's wiring (OFF_SQ: switched off for that call); S_ON/S_OFF act on step number
        ``step`` instead of S_NO."""
        self._commands.append((pin, step))
        self.fastpath.armed = False

    def set_level(self, pin: str, value: bool | None) -> None:
        """Override the level pin HALT_SQ, EN_IL or EN_SV with ``value`` from the next call
        on, whatever the pin's wiring (None: the pin decides again)."""
        if value is None:
            self.levels.pop(pin, None)
        else:
            self.levels[pin] = value
        self.fastpath.last_in = None  # the next call latches the pins again
        self.fastpath.armed = False  # and is a general one, which applies the levels

    def _apply_commands(self) -> None:
        st = self.st
        for pin, step in self._commands:
            if pin == "OFF_SQ":
                st.off = True
            else:
                st.rose.add(pin)
            if step is not None:
                self._target = step
        self._commands.clear()
        self.fastpath.last_in = None  # the next call latches the pins again (ends OFF_SQ)
        self.display.dirty = True

    # ------------------------------------------------------------ state changes

    def _raise(self, i: int, bit: int) -> None:
        st = self.st
        if not st.ev[i]:
            st.ev_steps.append(i)
        st.ev[i] |= bit
        st.log.append((i, bit))

    def _activate(self, i: int) -> None:
        st = self.st
        st.x[i] = True
        st.t_ns[i] = 0
        st.u_ns[i] = 0
        st.act_ns[i] = st.last_ns
        st.il_err[i] = False
        st.sv_err[i] = False
        st.active.append(i)
        k = self.cc.step_seq[i]
        if self.multi:
            self._by_seq[k].append(i)
        if k < self._done:
            self._late.append(i)
        st.entered.append(i)
        self._raise(i, EV_S1)

    def _deactivate(self, i: int) -> None:
        st = self.st
        st.x[i] = False
        st.active.remove(i)
        if self.multi:
            self._by_seq[self.cc.step_seq[i]].remove(i)
        st.left.append(i)
        self._final.append(i)
        st.il_err[i] = False
        if st.sv_err[i]:
            st.sv_err[i] = False
        st.il_ok[i] = True
        self._raise(i, EV_S0)

    def _all_off(self) -> None:
        st = self.st
        for i in list(st.active):
            self.off(i)

    def initialize(self) -> None:
        """INIT_SQ: every step off (final scan), errors cleared, the initial steps on."""
        st = self.st
        self._all_off()
        for i in range(st.n_steps):
            st.sv_err[i] = False
            st.il_err[i] = False
        for i in self.cc.initial:
            self._activate(i)

    def _entered(self) -> None:
        """The steps made active outside a call (``entering``: an online change's new
        sequencer) get their S1 event and stay for this call, as the first call's."""
        st = self.st
        for i in self.entering:
            if st.x[i] and i not in st.entered:
                st.entered.append(i)
                self._raise(i, EV_S1)
        self.entering = ()

    # ------------------------------------------------------------ one FB call

    def execute(self, inputs: dict[str, Any], now_ns: int) -> GraphState:
        """One FB call with the pin values ``inputs`` at clock time ``now_ns`` (docs/semantics.md,
        "One FB call"): the quiet call (``FastPath.quiet``) when it is one, else the general
        path."""
        quiet = self.quiet(inputs, now_ns)
        if quiet is not None:
            return quiet
        self.fastpath.armed = False  # until this call is done
        try:
            st = self._general(inputs, now_ns)
        except BaseException:  # a call cut short: the next one writes every output pin
            self.display.cut_short()
            raise
        if st.repin:  # the rows wrote input pins: into the instance DB, for the next call
            self.fastpath.repinned(inputs)
        return st

    def _general(self, inputs: dict[str, Any], now_ns: int) -> GraphState:
        """``execute`` when the call is not quiet: steps 1-6 of docs/semantics.md, "One FB call", in
        full."""
        st = self.st
        try:
            cur = self._getter(inputs)
        except KeyError:
            cur = None
        prog = self.prog
        # 1. latch inputs, edges, per-call lists, times
        ins = st.inputs
        rose = st.rose
        if rose:
            rose.clear()
        fp = self.fastpath
        if cur is None or cur != fp.last_in:
            fp.last_in = cur
            latch(self, inputs)
            self.display.dirty = True
        advance(self, now_ns)
        self._target = None
        if self._commands:
            self._apply_commands()
        self._new_call(st)
        self._done = -1  # step 2: no sequencer runs its rows (``on`` leaves the checks to 4.4)
        if self._carry:
            for i in self._carry:
                if st.x[i]:
                    self._raise(i, EV_S1)
            self._carry.clear()
        if self.display.dirty:  # else no input pin changed: no edge, same S_SEL
            self.display.page(st, ins, rose)

        # 2. OFF_SQ, INIT_SQ, modes, MAN requests, acknowledgement, registration
        if st.off and st.active:  # OFF_SQ, then INIT_SQ (docs/semantics.md, "One FB call", 2)
            self._all_off()
        if st.calls == 0 or "INIT_SQ" in rose:
            self.initialize()
        if self.entering:
            self._entered()
        if self._acked:
            self._acked.clear()
        if rose:
            self._requests(rose)
        if self.placing:
            place(self, self.placing)
            self.placing = ()
        if self._remote:
            self._release([i for i in self._remote if st.x[i] and st.sv_err[i]])
            self._remote.clear()
        st.calls += 1

        # 3. permanent before
        self._done = 0
        if self._permanent:
            prog.before(st, self)
        # 4. the sequencers
        mode = st.mode
        rule = MODE_RULES[mode]
        blocked = st.halted or st.off
        forced = self._acked if self._forcing and self._acked else ()
        # steps activated in step 2 (INIT_SQ, the first call, S_ON) stay for this call
        held = frozenset(st.entered) if st.entered and not self.codesys else frozenset()
        sw = (rule if mode != "AUTO" else None, "T_PUSH" in rose, blocked, forced, held)
        fast = (
            self.fast
            and mode == "AUTO"
            and not blocked
            and not forced
            and not held
            and not self.codesys
            and not st.sskip_enabled
        )
        if fast:
            fp.sequencers(st, self)
        elif self.multi:
            by_seq = self._by_seq
            for k in range(len(by_seq)):
                steps = by_seq[k]
                self._done = k
                if steps or self._final:
                    self._sequencer(k, steps, sw, rule)
            self._late_steps()
        else:
            self._sequencer(-1, st.active, sw, rule)
            if self.codesys:
                self._late_steps()
        # 5. permanent after
        if self._permanent:
            prog.after(st, self)
        # 6. group flags and outputs
        self._outputs()
        return st

    def _new_call(self, st: GraphState) -> None:
        """Clear the per-call lists (events, log, fired, entered, left, late steps) and OV and
        the ``Tn.TT`` of the transitions leaving the steps left in the last call; end the
        one-call pulse of the ``S0 N`` rows of the steps left in the last call (their
        operands back to 0 before anything of this call runs, docs/semantics.md, "Decisions":
        an event N row is a one-call pulse)."""
        self._done = 0
        if self._late:
            self._late.clear()
        if st.ev_steps:
            ev = st.ev
            for i in st.ev_steps:
                ev[i] = 0
            st.ev_steps.clear()
        if st.log:
            st.log.clear()
        if st.entered:
            st.entered.clear()
        if st.left:
            pulse = self.prog.pulse
            if pulse:  # the S0 N rows of the steps left in the last call: their pulse ends
                for i in st.left:
                    if pulse[i] is not None:
                        pulse[i](st)
            # a transition no longer valid is not satisfied: Tn.TT of the transitions leaving
            # the steps left back to 0 (step 4.1 evaluates those valid again); a step left and
            # entered again keeps its transitions valid (a join's other step, if left, is here)
            tt, leaving, x = st.tt, self.cc.leaving, st.x
            for i in st.left:
                if not x[i]:
                    for j in leaving[i]:
                        tt[j] = False
            st.left.clear()
        if self.passed:  # and those out of a step skip steps passed through
            tt, leaving = st.tt, self.cc.leaving
            for i in self.passed:
                for j in leaving[i]:
                    tt[j] = False
            self.passed.clear()
        if st.fired:
            st.fired.clear()
        st.ov = False

    def _requests(self, rose: set[str]) -> None:
        st = self.st
        st.mode = select_mode(st.mode, rose)
        if st.mode == "MAN" and not st.off and ("S_ON" in rose or "S_OFF" in rose):
            i = self.cc.step_index.get(st.s_no if self._target is None else self._target)
            if i is not None:
                if "S_ON" in rose and not st.x[i]:
                    self._activate(i)
                elif "S_OFF" in rose and st.x[i]:
                    self.off(i)
        acks: list[int] = []
        if "ACK_EF" in rose:
            acks = [i for i in st.active if st.sv_err[i]]
        elif "ACK_S" in rose:
            i = self.cc.step_index.get(st.s_no if self._target is None else self._target, -1)
            if i >= 0 and st.sv_err[i]:
                acks = [i]
        self._release(acks)
        if "REG_EF" in rose:
            for i in st.active:
                if st.il_err[i] or st.sv_err[i]:
                    self._raise(i, EV_R1)
        elif "REG_S" in rose:
            i = self.cc.step_index.get(st.s_no, -1)
            if i >= 0 and st.x[i]:
                self._raise(i, EV_R1)

    def _release(self, acks: Iterable[int]) -> None:
        """Acknowledge the supervision faults of ``acks``: releases each step for this call's
        switching (docs/semantics.md, "Supervision"); a cause that persists raises V1 again in step
        4d."""
        st = self.st
        for i in acks:
            st.sv_err[i] = False
            self._raise(i, EV_A1)
            self._raise(i, EV_V0)
            self._acked.add(i)

    def _sequencer(
        self, k: int, steps: list[int], sw: tuple[Any, ...], rule: Callable[[bool, bool], bool]
    ) -> None:
        """Sequencer ``k`` (-1: the only one) whose active steps are ``steps``; ``sw`` holds
        this call's switching options (see ``switching.switch``)."""
        if self.codesys:
            self._conditions_and_actions(k, steps)
            self._done = max(k, 0) + 1  # a step its transitions activate acts in the next call
            switch(self, steps, sw, rule)
        else:
            switch(self, steps, _held_now(self.st, steps, sw), rule)
            self._conditions_and_actions(k, steps)

    def _late_steps(self) -> None:
        """The steps activated in a sequencer whose rows had already run in this call — a
        jump or an ``ON Sx`` from a later sequencer of the FB: their interlock, supervision
        and rows run now, once, with their S1 event, as for every activation (S7-GRAPH
        manual 6-2, 6-4). With the CODESYS order they (and the steps a sequencer's own
        transitions activated) act in the next call instead."""
        late = self._late
        if late and self.codesys:
            self._carry = late[:]
            late.clear()
        elif late:
            st = self.st
            step_seq = self.cc.step_seq
            self._done = len(self._by_seq)
            for _ in range(st.n_steps):  # ON Sx in a late step's rows: one more round
                batch = [i for i in late if st.x[i]]
                late.clear()
                for k in sorted({step_seq[i] for i in batch}):
                    self._conditions_and_actions(k, [i for i in batch if step_seq[i] == k])
                if not late:
                    break
            late.clear()

    def _conditions_and_actions(self, k: int, steps: list[int]) -> None:
        """Steps d–e: interlock and supervision, final scans, action rows (docs/semantics.md, "One
        FB call", steps 4.4–4.5) of sequencer ``k`` (-1: the only one) whose active steps are
        ``steps``."""
        st = self.st
        prog = self.prog
        step_seq = self.cc.step_seq
        ev = st.ev
        check(self, steps)  # d: interlock and supervision of the active steps
        # e: final scans, then the action rows of active steps, in activation order
        fin = prog.fin
        final = self._final
        if final:
            keep: list[int] = []
            for i in final:
                if k >= 0 and step_seq[i] != k:
                    keep.append(i)
                else:
                    fin[i](st, self, ev[i] | EV_S0)
            final[:] = keep
        run_rows(self, steps, None)

    def _outputs(self) -> None:
        """Group flags and the FB outputs of docs/semantics.md, "One FB call", step 6 (display pins:
        display.py)."""
        st = self.st
        error = fault = False
        for i in st.active:
            if st.il_err[i]:
                error = True
            if st.sv_err[i]:
                fault = True
        st.error, st.fault = error, fault
        st.err_flt = error or fault
        disp = self.display
        if not self.fast:  # the reference: every output recomputed and copied, every call
            disp.dirty = True
        self.outs_written = disp.update(st)
        self.fastpath.armed = (
            self._lean
            and st.mode == "AUTO"
            and not (st.off or st.halted or st.sskip_enabled or self._commands or self._remote)
        )


def new_state(cc: CompiledChart) -> GraphState:
    """A fresh instance-DB content for ``cc``: pins at their defaults, variables at their
    initial values, no step active (the first call initializes, docs/semantics.md, "FB pins"
    INIT_SQ)."""
    st = GraphState(cc.n_steps, cc.n_transitions)
    st.inputs.update(input_defaults(cc.parameters, cc.options))
    st.outputs.update(output_defaults(cc.parameters, cc.options))
    st.vars.update(cc.var_inits)
    st.ackreq_enabled = cc.options.ack_required
    st.sskip_enabled = cc.options.skip_steps
    return st


def _held_now(st: GraphState, steps: list[int], sw: tuple[Any, ...]) -> tuple[Any, ...]:
    """``sw`` holding also the steps of ``steps`` an earlier sequencer activated in this call
    (a jump or ``ON Sx`` into this one): like a step INIT_SQ activated, such a step is
    active for this whole call — its transitions are evaluated, they switch in the next
    call — so it runs its S1 rows and is never left unseen (docs/semantics.md,
    "Decisions")."""
    ev = st.ev
    new = [i for i in steps if ev[i] & EV_S1]
    held: frozenset[int] = sw[4]
    if not new or held.issuperset(new):
        return sw
    return (*sw[:4], held.union(new))


def dated(cc: CompiledChart, state: GraphState) -> GraphState:
    """``state`` with its DATE and DATE_AND_TIME variables as dates again (a snapshot keeps
    them as ISO text, ``engine.blocks``)."""
    vars_ = state.vars
    for name, t in cc.var_types.items():
        if name in vars_:
            vars_[name] = from_stored(t, vars_[name])
    return state
