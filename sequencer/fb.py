"""GraphFB: a compiled chart as an engine FB (SPEC §2.2, §2.7; DESIGN "State lives in the
instance DB").

The FB's interface is the chart's parameter set (``sequencer.params``: IN pins, OUT pins)
plus one STAT ``G7_STATE`` of type OBJECT holding the ``GraphState`` — so snapshot/restore
of the instance DB persists the whole sequencer. OB1 calls the FB every scan; OB100 calls it
with INIT_SQ = 1 (``startup_obs``). Several GraphFBs may share one CPU. Each call emits
the step events of ``GraphState.log`` into the scan's ``ScanRecord.events`` as
``StepEvent`` values.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, NamedTuple

from s7graph.engine.blocks import FB, OB, Decl, InstanceDB, Var
from s7graph.engine.errors import BlockError
from s7graph.sequencer.compiled import CompiledChart, Program
from s7graph.sequencer.cycle import GraphRuntime, new_state
from s7graph.sequencer.messages import sync_messages
from s7graph.sequencer.params import (
    Direction,
    check_pin,
    input_defaults,
    is_pin,
    output_defaults,
    pins_for,
)
from s7graph.sequencer.state import GraphState
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


class GraphFB:
    """A ``CompiledChart`` bound to an engine FB number and an instance DB number."""

    def __init__(self, cc: CompiledChart, *, fb_number: int | None = None,
                 db_number: int | None = None, fast: bool = True) -> None:  # fmt: skip
        self.cc = cc
        self.fast = fast  # False: every call takes the general path (GraphRuntime ``fast``)
        self.fb_number = fb_number or cc.chart.fb_number or 1
        self.db_number = db_number or cc.chart.db_number or self.fb_number
        pins = pins_for(cc.parameters)
        self.in_pins = tuple(p for p in pins if p.direction is Direction.IN)
        self.out_pins = tuple(p.name for p in pins if p.direction is Direction.OUT)
        # initial values: EN_ACKREQ/EN_SSKIP hold the chart's options (params.OPTION_DEFAULTS)
        initial = input_defaults(cc.parameters, cc.options)
        initial.update(output_defaults(cc.parameters, cc.options))
        decl = {Direction.IN: Decl.IN, Direction.OUT: Decl.OUT}
        interface = [Var(p.name, p.type, decl[p.direction], initial[p.name]) for p in pins]
        interface.append(Var(STATE_VAR, "OBJECT", Decl.STAT, self._fresh_state))
        self.fb = FB(self.fb_number, cc.name, tuple(interface), self._body)
        self.idb: InstanceDB | None = None
        self._runtime: GraphRuntime | None = None
        self._prog: Program | None = None
        self._mem: Any = None
        self._ctx: Any = None
        self._messages = cc.options.messages
        self._name, self._step_numbers = cc.name, cc.step_numbers  # of the step events
        self._commands: list[tuple[str, int | None]] = []
        self._copied: Any = None  # the instance-DB values the outputs were last copied to
        # the next call may run flat from OB1 (startup_obs): the last one ran on ``_ctx``
        # with its runtime, without a message list, and no command is queued since
        self._flat = False

    def _fresh_state(self) -> GraphState:
        return new_state(self.cc)

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
        chart's parameter set is refused, naming the set (SPEC §2.7)."""
        for name in params:
            if is_pin(name):
                check_pin(name, self.cc.parameters, direction=Direction.IN)
        return ctx.call(self.fb, self.idb, **params)  # type: ignore[no-any-return]

    def runtime(self, mem: Any) -> GraphRuntime:
        """The runtime of this FB bound to ``mem`` (built once, rebound on a new state)."""
        st = self.state
        rt = self._runtime
        if rt is None or self._mem is not mem:
            self._prog = self.cc.bind(mem)
            self._mem = mem
            rt = GraphRuntime(self.cc, self._prog, st, call=self._call_block,
                              counter=self._counter, timer=self._timer, fast=self.fast)  # fmt: skip
            self._runtime = rt
            self._flat = False
        elif rt.st is not st:
            rt.rebind(st)
        return rt

    def command(self, pin: str, step: int | None = None) -> None:
        """An operator command for the next call: ``pin`` (ACK_EF, INIT_SQ, OFF_SQ, S_ON,
        S_OFF, T_PUSH, SW_*) as a one-call rising edge, whatever the parameter set; S_ON and
        S_OFF on step number ``step`` (``GraphRuntime.command``)."""
        self._commands.append((pin, step))
        self._flat = False

    # ------------------------------------------------------------ the FB body

    def _body(self, ctx: Any, idb: InstanceDB) -> None:
        self.idb = idb
        self._ctx = ctx
        values = idb.values
        rt = self._runtime
        if rt is None or self._mem is not ctx.mem or rt.st is not values[STATE_VAR]:
            rt = self.runtime(ctx.mem)
        if self._commands:
            for pin, step in self._commands:
                rt.command(pin, step)
            self._commands.clear()
        st = rt.execute(values, ctx.now_ns)
        self._copy_outputs(values, st, rt.outs_written)
        if self._messages:
            self._sync_messages(ctx, idb, rt, st)
        else:
            self._flat = True
        if st.log:
            self._emit_events(ctx, idb, st)

    def _copy_outputs(self, values: dict[str, Any], st: GraphState, names: tuple[str, ...]) -> None:
        """The output pins ``names`` this call wrote into the instance DB (all of them into
        another instance DB than last time)."""
        if self._copied is not values:
            names = self.out_pins
            self._copied = values
        out = st.outputs
        for name in names:
            values[name] = out[name]

    def _emit_events(self, ctx: Any, idb: InstanceDB, st: GraphState) -> None:
        """This call's step events into the scan record, as ``StepEvent`` values."""
        numbers, name, number, cycle = self._step_numbers, self._name, idb.number, ctx.cycle
        ctx.emit_all(  # tuple.__new__: a StepEvent without its Python __new__
            [_tuple_new(StepEvent, (name, number, numbers[i], _EVENT_OF_BIT[b], cycle))
             for i, b in st.log]
        )  # fmt: skip

    def _sync_messages(self, ctx: Any, idb: InstanceDB, rt: GraphRuntime, st: GraphState) -> None:
        """MESSAGES := TRUE (SPEC §2.10): bring the CPU's message list in line with this
        call's faults, queue the steps a user acknowledged there for the next call, and
        forward the list's new events into the scan record."""
        messages = message_list(ctx.cpu)
        acks = sync_messages(self.cc, st, messages, self.cc.name, idb.number, ctx.now_ns)
        if acks:
            rt.acknowledge(acks)
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
        counter_row(self._mem.counters, op, number, value)

    def _timer(self, op: str, number: int, value: Any) -> None:
        timer_row(self._mem.timers, op, number, value, self._ctx.now_ns)


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
    """TL (extended pulse), TD (retentive on-delay), TF (off-delay), TR (reset) on timer
    cell T ``number``: started once in the event call, then run by the CPU's time base."""
    cell = s5_timers.cell_of(cells, number)
    if op == "TR":
        s5_timers.reset(cell)
        return
    fn = {"TL": "SE", "TD": "SS", "TF": "SF"}[op]
    cell.s_edge = False
    s5_timers.run(cell, fn, True, int(value), now_ns)
    if op == "TF":
        s5_timers.run(cell, fn, False, int(value), now_ns)


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
            rt = g._runtime
            if g._flat and rt is not None and g._ctx is ctx:
                idb = g.idb
                assert idb is not None
                values = idb.values
                if rt.st is values[STATE_VAR]:
                    try:
                        st = rt.quiet(values, ctx.now_ns)
                        if st is not None:
                            names = rt.outs_written
                            if names or g._copied is not values:
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
    """Install several GraphFBs and their OB1/OB100 in ``cpu``."""
    items = list(fbs)
    for g in items:
        g.install(cpu)
    cpu.load(*startup_obs(*items))
