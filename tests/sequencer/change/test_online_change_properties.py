"""Online change as a property: a chart runs on a soft CPU while random sequences of edits
from the editor's table of operations are applied to it and downloaded into the running
FB (``sequencer.online.swap``) with every choice for removed active steps; the CPU runs on
with random contacts, clock steps and operator commands.

Oracle: the CPU never leaves RUN (no exception in any call) and its active steps are one
list; a download is refused only when it would drop active steps without a choice, and
carries the active steps by number with their times, variables and pins by name, and a
sequencer the running chart did not have starts in its initial steps (from 0, their S1
event in the next call); after each download the running FB scans exactly as a fresh FB of
the new chart started from the carried-over state (``twin``: a second CPU on the same clock
and contacts, told the same steps entered): per scan the same active steps, step events
(with their step numbers), FB outputs and watched operands (outputs, markers, a counter,
a timer).

Beside the chart the CPU runs an S7-SCL FB (FB17), which the random edits (and, drawn, the
start chart) call (``CALL FB 17, DB 12``) and whose variables their conditions then read by
name (``DB12.calls``): the editor and the download check those reads against the FB's
interface; a read of DB12 left with no call naming it (the call's row or step deleted) is
one error an edit may leave (E048), and its download is refused with E048, the CPU
running the old chart on. Some of the calls drawn do not fit FB17 (a parameter it lacks, a
REAL to its BOOL input, its output given with ``:=``): reached, each would stop the CPU; the
editor lists them as soon as they are made, exactly as the download then refuses them
(E047, ``sequencer.calls.unfit_calls``, as the compiler process does), and the editor
goes back to the running chart."""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from s7graph.engine.blocks import OB
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import CpuMode
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.calls import call_sites, unfit_calls
from s7graph.sequencer.change.edit import OPERATIONS, Argument, Session, make_edit
from s7graph.sequencer.change.online import SwapRefused, swap
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.fb import STATE_VAR
from s7graph.sequencer.text.format import quote
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sfb.alarms import message_list
from s7graph.web.harness.session import ChartLoadError, ChartSession, compile_model
from tests.paths import ROOT
from tests.sequencer.helpers import CHARTS
from tests.sequencer.test_user_fb_members import interfaces, scl_program

DRILL = ROOT / "examples" / "drill"


def _start(path: Path, symbols: Path | None = None) -> tuple[Chart, SymbolTable]:
    table = SymbolTable.from_file(symbols) if symbols is not None else SymbolTable()
    return parse_chart(path.read_text(encoding="utf-8"), path.name), table


STARTS = [
    *(CHARTS / f"{name}.s7g" for name in ("linear", "alternative", "simultaneous", "stop")),
    CHARTS / "two_sequencers.s7g",
    CHARTS / "jump.s7g",
    DRILL / "drill.s7g",
]

# What the random edits write: conditions TRUE/FALSE/contacts (and a step time, a counter),
# action rows on outputs, markers, a marker word, a counter and a timer. All valid in every
# start chart, so an edited chart that does not compile is a bug of the editor.
CONDITIONS = [
    "TRUE",
    "FALSE",
    "I0.0",
    "NOT I0.1",
    "I0.2 AND M0.1",
    "I0.3 OR MW4 > 3",
    "C1 > 2",
    "I0.4",
]
READS = ["DB12.calls > 2", "DB12.Running OR I0.5"]  # with a call of FB17, DB12 in the chart
ROWS = [
    {"qualifier": "N", "operand": "Q0.0"},
    {"qualifier": "S", "operand": "Q0.1", "event": "S1"},
    {"qualifier": "R", "operand": "Q0.1", "event": "S0"},
    {"qualifier": "D", "operand": "Q0.2", "value": "T#40MS"},
    {"qualifier": "L", "operand": "Q0.3", "value": "T#30MS"},
    {"qualifier": "N", "operand": "M0.1"},
    {"qualifier": "N", "operand": "MW4 := MW4 + 1", "event": "S1"},
    {"qualifier": "CU", "operand": "C1", "event": "S1"},
    {"qualifier": "TL", "operand": "T1", "value": "S5T#50MS", "event": "S1"},
    {"qualifier": "N", "operand": "Q0.4", "interlocked": True},
    {"qualifier": "S", "operand": "M0.2", "event": "V1"},
    {"qualifier": "R", "operand": "M0.2", "event": "L1"},
    {"qualifier": "CALL", "operand": "SFB 4, DB 10 (IN := I0.1, PT := T#50MS, Q => M1.0)"},
]
CALL_FB17 = {"qualifier": "CALL", "operand": "FB 17, DB 12 (start := I0.2)"}
BAD_CALLS = [  # reached, each stopped the CPU: the download refuses them (E047)
    {"qualifier": "CALL", "operand": "FB 17, DB 12 (start := I0.2, speed := 5)"},
    {"qualifier": "CALL", "operand": "FB 17, DB 12 (start := 2.5)"},
    {"qualifier": "CALL", "operand": "FB 17, DB 12 (Running := 5)"},
]
UNFIT = {  # what the download says of them
    "FB17 has no parameter speed (parameters: start, Running)",
    "FB17: start is BOOL, REAL does not fit it",
    "FB17: Running is an output, use Running => ...",
    "FB17: Running is BOOL, INT does not fit it",
}
PROGRAM = scl_program()  # FB17: Running after its third call with start, ``calls`` counted
BLOCKS = interfaces(PROGRAM.blocks)
UNCALLED = "DB12 is not an instance DB of this chart's calls"
"""The one error an edit may leave: a read of DB12 once no call names it (E048)."""


def chain(n: int, header: str = "") -> str:
    """A chain of ``n`` steps whose transitions are all ``TRUE``, back to S1 (FB 1)."""
    steps = "".join(
        f"  {'INITIAL_STEP' if k == 1 else 'STEP'} S{k}:\n  END_STEP\n" for k in range(1, n + 1)
    )
    arcs = "".join(
        f"  TRANSITION T{k} FROM S{k} TO S{k % n + 1} := TRUE;\n" for k in range(1, n + 1)
    )
    return (
        f'FUNCTION_BLOCK "Chain" FB 1 DB 1\n{header}SEQUENCE 1\n{steps}{arcs}'
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )


TEXTS: dict[str, list[str]] = {
    "name": ["", "Clamp"],
    "message": ["", "Work piece not clamped"],
    "condition": CONDITIONS,
    "option": ["SKIP_STEPS", "ACK_REQUIRED", "ORDER", "PARAMETERS", "MESSAGES"],
    "value": ["TRUE", "FALSE", "CODESYS", "MINIMUM", "STANDARD", "MAXIMUM"],
    "text": [
        chain(20),
        chain(20, "  PARAMETERS := STANDARD; MESSAGES := TRUE; ACK_REQUIRED := TRUE;\n"),
        chain(3, "  PARAMETERS := MAXIMUM;\n"),
    ],
}
EDITS = list(OPERATIONS)
COMMANDS = ["ACK_EF", "INIT_SQ", "SW_MAN", "SW_AUTO", "SW_TAP", "T_PUSH", "S_ON", "S_OFF"]


def _numbers(c: Chart, name: str) -> list[int]:
    """The numbers an argument may name in ``c``: existing ones and one spare."""
    if name in ("transition", "join"):
        used = [t.number for t in c.all_transitions()]
    elif name == "sequence":
        used = [q.number for q in c.sequences]
    elif name in ("index", "at"):
        return [0, 1, 2]
    else:
        used = [s.number for s in c.all_steps()]
    return [*used, max(used, default=0) + 1]


def _argument(c: Chart, a: Argument) -> st.SearchStrategy[Any]:
    if a.type == "RowFields":
        return st.sampled_from([*ROWS, CALL_FB17, *BAD_CALLS])
    if a.type == "bool":
        return st.booleans()
    if a.name == "text":  # a whole chart for the same block (a download keeps the block)
        block = f"{quote(c.name)}{f' FB {c.fb_number}' if c.fb_number else ''}"
        block += f" DB {c.db_number}" if c.db_number else ""
        return st.sampled_from(TEXTS["text"]).map(lambda t: t.replace('"Chain" FB 1 DB 1', block))
    if a.name == "condition" and any(x.call.instance == 12 for x in call_sites(c)):
        return st.sampled_from([*CONDITIONS, *READS])  # DB12's variables: a call names it
    if a.type == "str":
        return st.sampled_from(TEXTS[a.name])
    numbers = st.sampled_from(_numbers(c, a.name))
    return st.one_of(st.none(), numbers) if a.type.endswith("None") else numbers


@dataclass(frozen=True)
class Scan:
    """What one scan of a CPU shows of its GRAPH FB."""

    mode: CpuMode
    active: tuple[int, ...]
    events: tuple[tuple[int, str, int], ...]
    outputs: tuple[tuple[str, Any], ...]
    operands: tuple[Any, ...]


def _scan(cpu: ChartSession) -> Scan:
    record = cpu.scan()
    g = cpu.graph
    active = tuple(sorted(g.cc.step_numbers[i] for i in g.state.active))
    events = tuple((e.step, e.event, e.cycle) for e in record.events if hasattr(e, "step"))
    mem = cpu.cpu.mem
    operands = (
        bytes(mem.outputs[:2]),
        bytes(mem.markers[:8]),
        mem.counters[1].value,
        mem.timers[1].q,
    )
    return Scan(record.mode, active, events, tuple(sorted(g.outputs.items())), operands)


def twin(
    plant: ChartSession, queued: list[tuple[str, int | None]], entered: tuple[int, ...] = ()
) -> ChartSession:
    """A second CPU running a fresh GraphFB of the chart ``plant`` runs now, started from
    its carried-over state: the FB's instance DB (state and pins, restored from a snapshot
    as from a state file), those of the blocks its rows call, the memory, the message list
    and the cycle count copied, nothing run at its startup (an OB100 without the INIT_SQ
    call); the commands ``queued`` for the FB's next call queued there too, and the steps
    ``entered`` at the swap (a new sequencer's initial steps) given their S1 there."""
    g = plant.graph
    fresh = ChartSession(g.cc, plant.symbols, plant.clock, blocks=[PROGRAM])
    fresh.cpu.load(OB(100, "OB100", lambda ctx: None))
    fresh.start()
    fresh.cpu.cycle = plant.cpu.cycle
    mine, theirs = fresh.cpu.mem, plant.cpu.mem
    for area in ("inputs", "outputs", "markers", "periph_in", "periph_out"):
        getattr(mine, area)[:] = getattr(theirs, area)
    # cells of scalars: a copy of each is a deep copy (copy.deepcopy of the 512 cells was
    # most of a twin's time)
    mine.timers[:] = [copy.copy(cell) for cell in theirs.timers]
    mine.counters[:] = [copy.copy(cell) for cell in theirs.counters]
    message_list(fresh.cpu).restore(message_list(plant.cpu).snapshot())
    assert g.idb is not None and fresh.graph.idb is not None
    data = json.loads(json.dumps(g.idb.snapshot()))
    fresh.graph.idb.restore(data, strict=True)
    for number, idb in fresh.cpu.instance_dbs.items():  # those of the SFBs rows call, as
        if number != g.db_number:  # they are (a snapshot's IEC timer would lose time)
            idb.values.update(copy.deepcopy(plant.cpu.instance_dbs[number].values))
    for pin, step in queued:
        fresh.graph.command(pin, step)
    fresh.graph.enter(entered)
    return fresh


class OnlineChange(RuleBasedStateMachine):
    """A running chart, its editor, and the twin started from the last carried state."""

    def __init__(self) -> None:
        super().__init__()
        self.clock = VirtualClock()
        self.plant: ChartSession | None = None
        self.twin: ChartSession | None = None
        self.edits: list[str] = []
        self.queued: list[tuple[str, int | None]] = []  # commands for the next call

    @initialize(start=st.sampled_from(STARTS), call=st.booleans())
    def run_a_chart(self, start: Path, call: bool) -> None:
        """``start`` running; with ``call``, its first step calls FB17 (DB12) from the
        start, so that the edits' reads of DB12 compile."""
        symbols = DRILL / "symbols.txt" if start.parent == DRILL else None
        chart, table = _start(start, symbols)
        self.editor = Session.open(chart, table, BLOCKS)
        if call:
            first = chart.all_steps()[0].number
            self.editor = self.editor.apply(make_edit("add_row", {"step": first, "row": CALL_FB17}))
            chart = self.editor.chart
        cc, table = compile_model(chart, table, blocks=lambda _: BLOCKS)
        self.plant = ChartSession(cc, table, self.clock, blocks=[PROGRAM])
        self.plant.start()

    @rule(
        data=st.data(),
        n=st.integers(1, 4),
        removed=st.sampled_from([None, "keep", "init"]),
        scans=st.integers(0, 8),
    )
    def edit_and_download(
        self, data: st.DataObject, n: int, removed: str | None, scans: int
    ) -> None:
        """``n`` random edits in the editor (refused ones change nothing), the download of
        the chart into the running FB, and ``scans`` scans."""
        for _ in range(n):
            op = data.draw(st.sampled_from(EDITS), label="operation")
            c = self.editor.chart
            args = {a.name: data.draw(_argument(c, a), label=a.name) for a in op.arguments}
            after = self.editor.apply(make_edit(op.name, args))
            if after.refusal is None:
                self.edits.append(f"{op.name} {args}")
            self.editor = after
            errors = [
                d.message
                for d in after.diagnostics
                if d.is_error and UNCALLED not in d.message and d.code != "E047"
            ]
            assert not errors, f"{op.name} {args} after {self.edits[-8:-1]}: {errors[0]}"
            listed = [d for d in after.diagnostics if d.code == "E047"]  # before any download
            assert listed == unfit_calls(after.chart, after.symbols, BLOCKS), listed
        self.download(removed)
        self.run(data, scans)

    def download(self, removed: str | None) -> None:
        plant = self.plant
        assert plant is not None
        g = plant.graph
        try:
            new, table = compile_model(self.editor.chart, plant.symbols, blocks=lambda _: BLOCKS)
        except ChartLoadError as exc:  # a read of DB12 no call names: the old chart runs on
            assert self.editor.has_errors and all(UNCALLED in x for x in exc.lines if "error" in x)
            self.edits.append("download refused: E048")
            return
        unfit = unfit_calls(self.editor.chart, table, BLOCKS)
        if unfit:  # a call that does not fit FB17: refused as the compiler process does
            assert all(d.message in UNFIT for d in unfit), unfit
            assert self.editor.has_errors  # the editor listed them first
            self.edits.append("download refused: E047")
            self.editor = Session.open(g.cc.chart, plant.symbols, BLOCKS)  # edited back
            return
        old, before = g.cc, g.state
        active = sorted(old.step_numbers[i] for i in before.active)
        gone = tuple(n for n in active if n not in new.step_index)
        times = {n: before.step_t_ms(old.step_index[n]) for n in active}
        pins = {k: v for k, v in g.idb.values.items() if k != STATE_VAR} if g.idb else {}
        variables = dict(before.vars)
        try:
            report = swap(g, new, plant.cpu, removed=removed, user="eng")
        except SwapRefused:
            assert gone and removed is None
            self.edits.append(f"download refused, removed={removed}")
            return
        assert sorted(report.removed_active) == list(gone), (report.removed_active, gone)
        after = g.state  # carried by step number, variables and pins by name
        kept = [n for n in active if n not in gone]
        started = self.started(old, new, kept)
        assert [q.started for q in report.carry.sequencers] == [q[1] for q in started]
        entered = tuple(n for _, steps in started for n in steps)
        assert sorted(new.step_numbers[i] for i in after.active) == sorted([*kept, *entered])
        assert {n: after.step_t_ms(new.step_index[n]) for n in kept} == {n: times[n] for n in kept}
        assert all(after.step_t_ms(new.step_index[n]) == 0 for n in entered)
        assert after.vars == {
            k: variables.get(k, v) if new.var_types[k] == old.var_types.get(k) else v
            for k, v in after.vars.items()
        }
        assert g.idb is not None
        assert all(g.idb.values[k] == v for k, v in pins.items() if k in g.idb.values)
        plant.symbols = table  # the chart is the GraphFB's own
        self.edits.append(f"download removed={removed}")
        if report.initialized:
            self.queued.append(("INIT_SQ", None))
        self.twin = twin(plant, self.queued, entered)

    @staticmethod
    def started(
        old: CompiledChart, new: CompiledChart, kept: list[int]
    ) -> list[tuple[int, tuple[int, ...]]]:
        """The test's own oracle of a download's new sequencers: each sequencer number the
        running chart lacks, with its initial steps — none when a kept step moved into it."""
        out = []
        for number, steps in zip(new.seq_numbers, new.seq_steps, strict=True):
            if number in old.seq_numbers:
                continue
            numbers = [new.step_numbers[i] for i in steps]
            initial = tuple(new.step_numbers[i] for i in steps if i in new.initial)
            out.append((number, () if any(n in kept for n in numbers) else initial))
        return out

    @rule(data=st.data(), scans=st.integers(1, 12))
    def run(self, data: st.DataObject, scans: int) -> None:
        assert self.plant is not None
        for _ in range(scans):
            contacts = data.draw(st.integers(0, 31), label="IB0")
            ms = data.draw(st.sampled_from([1, 10, 10, 30, 60]), label="ms")
            self.clock.advance(ms)
            for cpu in (self.plant, self.twin):
                if cpu is not None:
                    cpu.set("IB0", contacts)
            got = _scan(self.plant)
            self.queued.clear()
            assert got.mode is CpuMode.RUN, self._why()
            if self.twin is not None:
                expected = _scan(self.twin)
                assert got == expected, (got, expected, self.edits)

    @rule(data=st.data(), pin=st.sampled_from(COMMANDS), pick=st.integers(0, 20))
    def command(self, data: st.DataObject, pin: str, pick: int) -> None:
        """An operator command, and the scan whose call takes it."""
        assert self.plant is not None
        numbers = self.plant.graph.cc.step_numbers
        step = numbers[pick % len(numbers)] if pin in ("S_ON", "S_OFF") else None
        for cpu in (self.plant, self.twin):
            if cpu is not None:
                cpu.graph.command(pin, step, user="olga")
        self.run(data, 1)

    @rule(data=st.data(), pin=st.sampled_from(["HALT_SQ", "EN_IL", "EN_SV"]), value=st.booleans())
    def level(self, data: st.DataObject, pin: str, value: bool) -> None:
        """A level override (HALT_SQ, EN_IL, EN_SV), and the scan whose call takes it."""
        for cpu in (self.plant, self.twin):
            if cpu is not None:
                cpu.graph.set_level(pin, value)
        self.run(data, 1)

    @invariant()
    def runs_with_one_list_of_active_steps(self) -> None:
        if self.plant is not None:
            assert self.plant.cpu.mode is CpuMode.RUN, self._why()
            state = self.plant.graph.state
            assert sorted(state.active) == [i for i, x in enumerate(state.x) if x], self.edits

    def _why(self) -> str:
        assert self.plant is not None
        lines = [str(d) for d in self.plant.cpu.diagnostics.since(0)][-4:]
        return "\n".join([*lines, *self.edits])


OnlineChange.TestCase.settings = settings(
    max_examples=100,
    stateful_step_count=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
test_online_change_runs_on_as_a_fresh_fb_of_the_new_chart = OnlineChange.TestCase
