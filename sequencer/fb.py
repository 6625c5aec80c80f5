"""GraphFB: a compiled chart as an engine FB (docs/semantics.md, "One FB call" and "FB pins";
docs/architecture.md, "The core is a function").

The FB's interface is the chart's parameter set (``sequencer.params``: IN pins, OUT pins)
plus one STAT ``G7_STATE`` of type OBJECT holding the ``GraphState`` — so snapshot/restore
of the instance DB persists the whole sequencer. OB1 calls the FB every scan; OB100 calls it
with INIT_SQ = 1 (``startup_obs``), and so does OB102 after a cold restart. Several
GraphFBs may share one CPU. Each call emits the step events of ``GraphState.log`` into the
scan's ``ScanRecord.events`` as ``StepEvent`` values.

Restarts (``GraphFB.on_startup``, a CPU startup hook): the sequencer's position — active
steps with T and U, faults, the mode — is written to the diagnostic buffer, before a warm or
cold restart initializes it, or as a hot restart (OB101) resumes it as it was, step times
included (the time the CPU was down or in STOP is not counted, as no call saw it). A
restart never acknowledges a message: one whose fault the restart clears goes *outgoing*
with the restart as its reason and stays listed until someone acknowledges it. The instance
data is recognised on disk by the compiled chart (``sequencer/change/carry.py``).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, NamedTuple

from s7graph.engine.blocks import FB, OB, Decl, InstanceDB, Var
from s7graph.engine.diagnostics import EventId
from s7graph.engine.errors import BlockError
from s7graph.engine.restart import RestartType
from s7graph.sequencer.change.carry import ChartFormat
from s7graph.sequencer.compiled import CompiledChart, Program
from s7graph.sequencer.cycle import GraphRuntime, new_state
from s7graph.sequencer.messages import PROGRAM_USER, forget_removed, sync_messages
from s7graph.sequencer.params import (
    Direction,
    check_pin,
    input_defaults,
    is_pin,
    output_defaults,
    pins_for,
)
from s7graph.sequencer.state import COMMAND_PINS, LEVEL_PINS, GraphState
from s7graph.sequencer.sync import SyncStep, synchronization
from s7graph.sfb import s5_counters, s5_timers
from s7graph.sfb.alarms import message_list
from s7graph.steps.qualifiers import EVENT_NAMES

STATE_VAR = "G7_STATE"
_tuple_new = tuple.__new__
_EVENT_OF_BIT = {1 << k: name for k, name in enumerate(EVENT_NAMES)}


class StepEvent(NamedTuple):
    """One step event (S1 S0 V1 V0 L1 L0 A1 R1) of a GRAPH FB call, for the ScanRecord
    (immutable; a named tuple because a scan may carry hundreds of them)."""

    fb: str
    db: int
    step: int
    event: str
    cycle: int

    def __str__(self) -> str:
        return f"{self.fb}/DB{self.db} S{self.step} {self.event} @{self.cycle}"


class LoadedChart:
    """Everything a :class:`GraphFB` derives from the chart it runs: the compiled chart, the
    engine FB (its interface is the chart's parameter set), the pins, the step numbers of
    its events, whether it keeps a message list, and the runtime bound to the CPU's memory
    (the cycle's tables, display and fast path) with what the flat call of OB1 relies on.
    One object: an online change replaces it whole, so nothing of the old chart stays
    beside the new one."""

    __slots__ = (
        "cc",
        "copied",
        "fb",
        "flat",
        "in_pins",
        "mem",
        "messages",
        "name",
        "out_pins",
        "prog",
        "runtime",
        "step_numbers",
    )

    def __init__(self, cc: CompiledChart, fb_number: int, body: Any) -> None:
        self.cc = cc
        pins = pins_for(cc.parameters)
        self.in_pins = tuple(p for p in pins if p.direction is Direction.IN)
        self.out_pins = tuple(p.name for p in pins if p.direction is Direction.OUT)
        # initial values: EN_ACKREQ/EN_SSKIP hold the chart's options (params.OPTION_DEFAULTS)
        initial = input_defaults(cc.parameters, cc.options)
        initial.update(output_defaults(cc.parameters, cc.options))
        decl = {Direction.IN: Decl.IN, Direction.OUT: Decl.OUT}
        interface = [Var(p.name, p.type, decl[p.direction], initial[p.name]) for p in pins]
        interface.append(Var(STATE_VAR, "OBJECT", Decl.STAT, lambda: new_state(cc)))
        self.fb = FB(
            fb_number, cc.name, tuple(interface), body, state_format=ChartFormat(cc, STATE_VAR)
        )
        self.messages = cc.options.messages
        self.name, self.step_numbers = cc.name, cc.step_numbers  # of the step events
        self.runtime: GraphRuntime | None = None  # built at the first call (GraphFB.runtime)
        self.prog: Program | None = None
        self.mem: Any = None  # the memory ``runtime`` is bound to
        self.copied: Any = None  # the instance-DB values the outputs were last copied to
        # the next call may run flat from OB1 (startup_obs): the last one ran on the FB's
        # context with this runtime, without a message list, and no command or level is
        # queued since
        self.flat = False


def chart_variables(idb: InstanceDB) -> tuple[dict[str, Any], dict[str, str]] | None:
    """The chart's own variables (its ``VAR``) in a GraphFB's instance DB — their values,
    kept in the ``GraphState``, and their declared types — as S7-GRAPH keeps an FB's static
    variables in its instance DB; None for an instance DB of another FB."""
    fmt = idb.fb.state_format
    state = idb.values.get(fmt.state_var) if isinstance(fmt, ChartFormat) else None
    if not isinstance(fmt, ChartFormat) or not isinstance(state, GraphState):
        return None
    return state.vars, fmt.cc.var_types


class GraphFB:
    """A ``CompiledChart`` bound to an engine FB number and an instance DB number; what it
    derives from the chart is one :class:`LoadedChart` (``loaded``)."""

    def __init__(
        self,
        cc: CompiledChart,
        *,
        fb_number: int | None = None,
        db_number: int | None = None,
        fast: bool = True,
    ) -> None:
        self.fast = fast  # False: every call takes the general path (GraphRuntime ``fast``)
        self.fb_number = fb_number or cc.chart.fb_number or 1
        self.db_number = db_number or cc.chart.db_number or self.fb_number
        self.loaded = LoadedChart(cc, self.fb_number, self._body)
        self.idb: InstanceDB | None = None
        self._ctx: Any = None
        self._restart = ""  # the reason a startup OB's call gives its messages
        self._swapped = False  # a download swapped the chart: gone steps' messages go

    @property
    def cc(self) -> CompiledChart:
        """The compiled chart this FB runs."""
        return self.loaded.cc

    @property
    def fb(self) -> FB:
        """The engine FB: its interface is the chart's parameter set and ``G7_STATE``."""
        return self.loaded.fb

    @property
    def in_pins(self) -> tuple[Any, ...]:
        return self.loaded.in_pins

    @property
    def out_pins(self) -> tuple[str, ...]:
        return self.loaded.out_pins

    # ------------------------------------------------------------ engine wiring

    def install(self, cpu: Any) -> InstanceDB:
        """Load the FB into ``cpu`` and create its instance DB."""
        cpu.load(self.fb)
        self.idb = cpu.create_instance_db(self.db_number, self.fb, name=self.cc.name)
        return self.idb

    @property
    def state(self) -> GraphState:
        if self.idb is None:
            raise BlockError(f"{self.cc.name}: not installed in a CPU")
        return self.idb.values[STATE_VAR]  # type: ignore[return-value]

    @property
    def outputs(self) -> dict[str, Any]:
        """The FB output pins after the last call (S_NO, ERR_FLT, AUTO_ON, ...)."""
        if self.idb is None:
            return {}
        v = self.idb.values
        return {name: v[name] for name in self.out_pins}

    def call(self, ctx: Any, **params: Any) -> dict[str, Any]:
        """Call the FB from an OB body (``ctx.call`` with its instance DB). A pin outside the
        chart's parameter set is refused, naming the set (docs/semantics.md, "FB pins")."""
        for name in params:
            if is_pin(name):
                check_pin(name, self.cc.parameters, direction=Direction.IN)
        return ctx.call(self.fb, self.idb, **params)  # type: ignore[no-any-return]

    def runtime(self, mem: Any) -> GraphRuntime:
        """The runtime of this FB bound to ``mem`` (built once, rebound on a new state)."""
        st = self.state
        c = self.loaded
        rt = c.runtime
        if rt is None or c.mem is not mem:
            cpu = getattr(self._ctx, "cpu", None)
            c.prog = c.cc.bind(mem, getattr(cpu, "instance_dbs", None))
            c.mem = mem
            rt = GraphRuntime(
                c.cc,
                c.prog,
                st,
                call=self._call_block,
                counter=self._counter,
                timer=self._timer,
                fast=self.fast,
            )
            c.runtime = rt
            c.flat = False
        elif rt.st is not st:
            rt.rebind(st)
        return rt

    def on_startup(self, cpu: Any, restart: RestartType) -> None:
        """A CPU startup begins (``Cpu.add_startup_hook``): the position goes to the
        diagnostic buffer — before a warm or cold restart initializes it, or as a hot
        restart resumes it; the step times go on from where they were at the first call,
        whatever the clock now says (another process, time in STOP)."""
        if self.idb is None:
            return
        st = self.state
        if st.calls:
            what = "resumes" if restart is RestartType.HOT else "initializes"
            cpu.diagnostics.record(
                cpu.clock.now_ns(),
                EventId.SEQUENCER_POSITION,
                self.fb.label,
                f"{restart} restart {what} {self.cc.name}/DB{self.db_number}, "
                + position(self.cc, st),
            )
        st.last_ns = -1
        ob = {RestartType.WARM: 100, RestartType.HOT: 101, RestartType.COLD: 102}[restart]
        self._restart = f"{restart} restart (OB{ob})"

    def command(self, pin: str, step: int | None = None, *, user: str | None = None) -> None:
        """An operator command for the next call: ``pin`` (ACK_EF, ACK_S, INIT_SQ, OFF_SQ,
        S_ON, S_OFF, T_PUSH, SW_*) as a one-call rising edge, whatever the parameter set;
        S_ON, S_OFF and ACK_S on step number ``step`` (``GraphRuntime.command``). Messages
        the command acknowledges are acknowledged as ``user`` (default ``program``). Kept
        in the instance DB (``GraphState.to_command``) until that call, as ``place``."""
        if pin not in COMMAND_PINS:
            raise ValueError(f"{self.cc.name}: {pin!r} is not an edge pin a command acts as")
        st = self.state
        st.to_command = [*st.to_command, (pin, step, user)]
        self.loaded.flat = False

    def place(self, steps: Iterable[int]) -> None:
        """Place the sequence at step numbers ``steps`` in the next call, in MAN: in each
        sequence holding one of them exactly those active (``sequencer.placing``). Kept in
        the instance DB (``GraphState.to_place``) until that call: a restart from the state
        file in between carries it out in its first call."""
        self.state.to_place = list(steps)
        self.loaded.flat = False

    def enter(self, steps: Iterable[int]) -> None:
        """Step numbers ``steps``, made active outside a call (an online change's new
        sequencer: ``sequencer.change.carry``), get their S1 event in the next call and stay
        for it, as the steps the first call after a start activates. Kept in the instance DB
        (``GraphState.to_enter``) until that call, as ``place``: S1 once, restart or not."""
        st = self.state
        st.to_enter = list(dict.fromkeys([*st.to_enter, *steps]))
        self.loaded.flat = False

    def set_level(self, pin: str, value: bool | None) -> None:
        """Override HALT_SQ, EN_IL or EN_SV from the next call on (None: the pin decides
        again), whatever the parameter set (``GraphRuntime.set_level``). Kept in the
        instance DB (``GraphState.to_level``) until that call, as ``command``."""
        if pin not in LEVEL_PINS:
            raise ValueError(f"{self.cc.name}: {pin!r} is not a level pin (HALT_SQ EN_IL EN_SV)")
        st = self.state
        st.to_level = {**st.to_level, pin: value}
        self.loaded.flat = False

    @property
    def levels(self) -> dict[str, bool]:
        """The level overrides in force (kept in the instance DB's ``GraphState``)."""
        return dict(self.state.levels) if self.idb is not None else {}

    def synchronization(self) -> tuple[SyncStep, ...]:
        """Every step judged against the current process values (``sequencer.sync``); call
        between scans. A BlockError until the FB has been called once (its conditions are
        bound to the CPU's memory at the first call)."""
        prog = self.loaded.prog
        if prog is None or self.idb is None:
            raise BlockError(f"{self.cc.name}: not called yet, nothing to judge")
        return synchronization(self.cc, prog, self.state)

    def replace_chart(self, cc: CompiledChart, state: GraphState, cpu: Any) -> None:
        """Online change: run ``cc`` from the next call on, with ``state`` (the running state
        carried over to ``cc`` by ``sequencer.change.carry.carry_over``); call at a scan boundary.
        Everything derived from the old chart goes with its :class:`LoadedChart`. The FB
        keeps its number and its instance DB number; the instance DB is made anew for the
        new parameter set, each pin keeping its value by name. One-call commands queued for
        the next call, a placement or an entry not carried out yet and the level overrides
        in force (HALT_SQ, EN_IL, EN_SV) stay."""
        loaded = LoadedChart(cc, self.fb_number, self._body)
        old = self.idb
        cpu.load(loaded.fb)
        idb = cpu.replace_instance_db(self.db_number, loaded.fb, name=cc.name)
        if old is not None:
            for name, value in old.values.items():
                if name != STATE_VAR and name in idb.values:
                    idb.values[name] = value
            was = old.values.get(STATE_VAR)
            if isinstance(was, GraphState):  # what is not carried out yet stays
                state.to_enter, state.to_place = list(was.to_enter), list(was.to_place)
                state.to_command, state.to_release = list(was.to_command), list(was.to_release)
                state.to_level = {**was.levels, **was.to_level}  # in force again in the new
        idb.values[STATE_VAR] = state
        self.loaded = loaded
        self.idb = idb
        self._swapped = True

    # ------------------------------------------------------------ the FB body

    def _body(self, ctx: Any, idb: InstanceDB) -> None:
        self.idb = idb
        self._ctx = ctx
        values = idb.values
        c = self.loaded
        rt = c.runtime
        if rt is None or c.mem is not ctx.mem or rt.st is not values[STATE_VAR]:
            rt = self.runtime(ctx.mem)
        st = rt.st
        acting = None
        if st.to_level or st.to_command or st.to_place or st.to_enter or st.to_release:
            acting = self._pending(rt, st)
        st = rt.execute(values, ctx.now_ns)
        self._copy_outputs(values, st, rt.outs_written)
        if c.messages:
            self._sync_messages(ctx, idb, st, acting)
        else:
            c.flat = True
        if st.log:
            self._emit_events(ctx, idb, st)

    def _pending(self, rt: GraphRuntime, st: GraphState) -> tuple[str, int | None] | None:
        """What the instance DB holds for this call — level overrides, operator commands
        (``set_level``, ``command``), the placement and the entry (``place``, ``enter``),
        the steps users released in the message list (``_sync_messages``) — handed to the
        runtime (a step number the chart no longer has is dropped) and taken out of the DB:
        carried out once. Returns who commanded (the user and ACK_S step of the last
        command given a user), who acknowledges what the call releases."""
        for pin, value in st.to_level.items():
            rt.set_level(pin, value)
        acting = None
        for pin, step, user in st.to_command:
            rt.command(pin, step)
            if user is not None:
                acting = (user, step if pin == "ACK_S" else None)
        index = self.cc.step_index
        rt.placing = tuple(index[n] for n in st.to_place if n in index)
        rt.entering = tuple(index[n] for n in st.to_enter if n in index)
        if st.to_release:
            rt.acknowledge(index[n] for n in st.to_release if n in index)
        rt.fastpath.armed = False
        st.to_level, st.to_command, st.to_place, st.to_enter = {}, [], [], []
        st.to_release = []
        return acting

    def _copy_outputs(self, values: dict[str, Any], st: GraphState, names: tuple[str, ...]) -> None:
        """The output pins ``names`` this call wrote into the instance DB (all of them into
        another instance DB than last time)."""
        c = self.loaded
        if c.copied is not values:
            names = c.out_pins
            c.copied = values
        out = st.outputs
        for name in names:
            values[name] = out[name]

    def _emit_events(self, ctx: Any, idb: InstanceDB, st: GraphState) -> None:
        """This call's step events into the scan record, as ``StepEvent`` values."""
        c = self.loaded
        numbers, name, number, cycle = c.step_numbers, c.name, idb.number, ctx.cycle
        ctx.emit_all(  # tuple.__new__: a StepEvent without its Python __new__
            [
                _tuple_new(StepEvent, (name, number, numbers[i], _EVENT_OF_BIT[b], cycle))
                for i, b in st.log
            ]
        )

    def _sync_messages(
        self,
        ctx: Any,
        idb: InstanceDB,
        st: GraphState,
        acting: tuple[str, int | None] | None = None,
    ) -> None:
        """MESSAGES := TRUE (docs/semantics.md, "Messages"): bring the CPU's message list in line
        with this call's faults, queue the steps a user acknowledged there for the next call
        (``GraphState.to_release``, in the instance DB: a restart in between keeps them), and
        forward the list's new events into the scan record. ``acting``: the user (and ACK_S
        step) of this call's operator command, who acknowledges what it releases."""
        messages = message_list(ctx.cpu)
        user, target = acting if acting is not None else (PROGRAM_USER, None)
        restart = self._restart if ctx.ob in (100, 102) else ""
        acks = sync_messages(
            self.cc,
            st,
            messages,
            self.cc.name,
            idb.number,
            ctx.now_ns,
            user=user,
            step=target,
            restart=restart,
        )
        if acks:  # released in the next call; in the instance DB until then (``_pending``)
            numbers = self.cc.step_numbers
            st.to_release = list(dict.fromkeys([*st.to_release, *(numbers[i] for i in acks)]))
        if self._swapped:
            self._swapped = False
            forget_removed(st, messages, self.cc.name, idb.number, ctx.now_ns)
        alarm = getattr(ctx, "alarm", None)
        if alarm is not None:
            for event in messages.pop_events():
                alarm(event)

    # ------------------------------------------------------------ callbacks of action rows

    def _call_block(self, kind: str, block: Any, instance: Any, params: dict[str, Any]) -> Any:
        ref = f"{kind}{block}" if kind and isinstance(block, int) else block
        inst = instance
        if isinstance(instance, str) and instance.upper().startswith("DB"):
            inst = int(instance[2:])
        return self._ctx.call(ref, inst, **params)

    def _counter(self, op: str, number: int, value: Any) -> None:
        counter_row(self.loaded.mem.counters, op, number, value)

    def _timer(self, op: str, number: int, value: Any) -> None:
        timer_row(self.loaded.mem.timers, op, number, value, self._ctx.now_ns)


def counter_row(cells: Any, op: str, number: int, value: Any) -> None:
    """CS (load BCD ``C#``), CU, CD, CR on counter cell C ``number`` (event rows: once)."""
    cell = s5_counters.cell_of(cells, number)
    if op == "CS":
        cell.s_edge = False
        s5_counters.set_preset(cell, True, int(value))
    elif op == "CU":
        cell.cu_edge = False
        s5_counters.count_up(cell, True)
    elif op == "CD":
        cell.cd_edge = False
        s5_counters.count_down(cell, True)
    else:
        s5_counters.reset(cell, True)


def timer_row(cells: Any, op: str, number: int, value: Any, now_ns: int) -> None:
    """A timer row on cell T ``number`` in the call its event occurs (docs/semantics.md,
    "Actions", timer rows): TL starts an extended pulse (SE), TD a latching on delay (SS) —
    both restarted by every occurrence of the event, TD with its bit 0 again for the time —,
    TF an off delay (SF) whose start input is the event, a one-call pulse (the bit 1 at
    once, the time running from the next scan), TR stops and resets. ``value`` is the time,
    an S5TIME word; the CPU's time base runs the timer from then on."""
    cell = s5_timers.cell_of(cells, number)
    if op == "TR":
        s5_timers.reset(cell)
    elif op == "TL":
        s5_timers.start(cell, "SE", int(value), now_ns)
    elif op == "TD":
        s5_timers.reset(cell)
        s5_timers.start(cell, "SS", int(value), now_ns)
    elif op == "TF":
        s5_timers.start_off_delay_at_next_update(cell, int(value), now_ns)
    else:
        raise ValueError(f"{op}: not a timer qualifier (TL TD TF TR)")


def position(cc: CompiledChart, st: GraphState, limit: int = 8) -> str:
    """Where a sequencer is, in one line: its active steps (number, name, T and U,
    faults), the mode; ``limit`` steps at most."""
    parts = []
    for i in sorted(st.active, key=cc.step_numbers.__getitem__)[:limit]:
        text = (
            f"S{cc.step_numbers[i]} {cc.step_names[i]!r} "
            f"T={st.step_t_ms(i)} ms U={st.step_u_ms(i)} ms"
        )
        if st.sv_err[i]:
            text += " supervision fault"
        if st.il_err[i]:
            text += " interlock error"
        parts.append(text)
    if len(st.active) > limit:
        parts.append(f"and {len(st.active) - limit} more")
    where = "; ".join(parts) if parts else "no step active"
    return f"in {where} (mode {st.mode})"


def startup_obs(*fbs: GraphFB, extra_ob1: Any = None) -> tuple[OB, OB]:
    """OB1 calling every GraphFB in order, and OB100 calling each with INIT_SQ = 1.

    OB1 runs an FB's quiet call flat (``_run_flat``); any other call goes through
    ``CallContext.run_fb``."""

    def ob1_body(ctx: Any) -> None:
        run = getattr(ctx, "run_fb", None)  # engine.cpu.CallContext: no outputs dict
        if run is None:
            for g in fbs:
                ctx.call(g.fb, g.idb)
        elif ctx.depth < ctx.cpu.max_nesting:
            _run_flat(ctx, fbs, run)
        else:  # too deep: run_fb raises NestingOverflow
            for g in fbs:
                run(g.fb, g.idb)
        if extra_ob1 is not None:
            extra_ob1(ctx)

    def ob100_body(ctx: Any) -> None:
        for g in fbs:
            ctx.call(g.fb, g.idb, INIT_SQ=True)
            assert g.idb is not None
            g.idb.values["INIT_SQ"] = False

    return OB(1, "OB1", ob1_body), OB(100, "OB100", ob100_body)


def cold_restart_ob(*fbs: GraphFB) -> OB:
    """OB102: after a cold restart (instance DBs at their initial values) each GraphFB is
    called with INIT_SQ = 1, as OB100 does after a warm restart."""
    ob100 = startup_obs(*fbs)[1]
    return OB(102, "OB102", ob100.body)


def _run_flat(ctx: Any, fbs: tuple[GraphFB, ...], run: Any) -> None:
    """OB1's calls of ``fbs``, each quiet call (``GraphRuntime.quiet``) straight from this
    loop: what ``CallContext.run_fb`` and ``GraphFB._body`` do around it, without their
    call layers — one nesting level deeper (a block a row calls nests as from the FB),
    what escapes tagged with the FB (``CallContext.tag_fault``), then the written output
    pins into the instance DB and the step events into the scan record. A call that is
    not quiet, or an FB that has not run on this context, memory and state, or has a
    command queued or a message list to bring in line (``_flat``), goes through
    ``run_fb``."""
    depth = ctx.depth
    ctx.depth = depth + 1
    try:
        for g in fbs:
            c = g.loaded
            rt = c.runtime
            if c.flat and rt is not None and g._ctx is ctx:
                idb = g.idb
                assert idb is not None
                values = idb.values
                if rt.st is values[STATE_VAR]:
                    try:
                        st = rt.quiet(values, ctx.now_ns)
                        if st is not None:
                            names = rt.outs_written
                            if names or c.copied is not values:
                                g._copy_outputs(values, st, names)
                            if st.log:
                                g._emit_events(ctx, idb, st)
                            continue
                    except BaseException as exc:
                        fault = ctx.tag_fault(g.fb.label, exc)
                        if fault is exc:
                            raise
                        raise fault from exc
            ctx.depth = depth
            run(g.fb, g.idb)
            ctx.depth = depth + 1
    finally:
        ctx.depth = depth


def install_all(cpu: Any, fbs: Iterable[GraphFB]) -> None:
    """Install several GraphFBs and their OB1/OB100/OB102 in ``cpu``, each with its
    startup hook (``GraphFB.on_startup``)."""
    items = list(fbs)
    for g in items:
        g.install(cpu)
        add_hook = getattr(cpu, "add_startup_hook", None)
        if add_hook is not None:
            add_hook(g.on_startup)
    cpu.load(*startup_obs(*items), cold_restart_ob(*items))
