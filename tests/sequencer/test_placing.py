"""Placing the sequence (docs/semantics.md, "Synchronization"): in MAN, the steps an
operator names become the active ones of their sequences in one call — the others leave
with their final scan (S0), the named ones enter (S1) — and a sequence holding none of
them keeps its steps. A running FB placed at random moments scans as a fresh FB started
from its state with the same placement, and ends where S_OFF and S_ON one step at a time
would have put it."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from s7graph.engine.clock import VirtualClock
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.placing import moves
from s7graph.web.harness.session import ChartSession, compile_model
from tests.sequencer.change.test_online_change_properties import (
    DRILL,
    STARTS,
    _scan,
    _start,
    twin,
)
from tests.sequencer.helpers import Run, chart, seq

LINE = seq("""
  INITIAL_STEP S1 "Ready": END_STEP
  STEP S2 "Clamp": N Q0.0; END_STEP
  STEP S3 "Drill": N Q0.1; S1 S M0.0; END_STEP
  STEP S4 "Lift": N Q0.2; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
  TRANSITION T3 FROM S3 TO S4 := I0.2;
  TRANSITION T4 FROM S4 TO S1 := I0.3;
""")

TWO = seq(
    """
  INITIAL_STEP S1 "a": N Q0.0; END_STEP
  STEP S2 "b": N Q0.1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
""",
    1,
) + seq(
    """
  INITIAL_STEP S11 "c": N Q1.0; END_STEP
  STEP S12 "d": N Q1.1; END_STEP
  TRANSITION T11 FROM S11 TO S12 := I1.0;
  TRANSITION T12 FROM S12 TO S11 := I1.1;
""",
    2,
)


def _place(run: Run, *numbers: int) -> None:
    run.rt.placing = tuple(run.idx(n) for n in numbers)
    run.call()


def _man(sequences: str) -> Run:
    """The chart of ``sequences`` after its first call, switched to MAN."""
    run = chart(sequences)
    run.call()
    run.pulse("SW_MAN")
    assert run.st.mode == "MAN"
    return run


def test_a_placement_in_man_makes_the_named_steps_the_active_ones_in_one_call() -> None:
    run = _man(LINE)
    assert run.active == [1]
    _place(run, 3)
    assert run.active == [3]
    assert run.events(1) == {"S0"} and run.events(3) == {"S1"}
    assert run.get("Q0_1") and run.get("M0_0")  # S3's N row and its S1 row ran in that call
    assert not run.get("Q0_0")  # no call ran S1 beside S3, nor none at all


def test_the_step_left_runs_its_final_scan() -> None:
    run = _man(LINE)
    _place(run, 2)
    assert run.get("Q0_0")
    _place(run, 4)
    assert run.active == [4] and not run.get("Q0_0") and run.get("Q0_2")


def test_a_placement_outside_man_changes_nothing() -> None:
    run = chart(LINE)
    run.call()
    _place(run, 3)
    assert run.active == [1]
    assert run.events(3) == set()


def test_a_sequence_holding_none_of_the_named_steps_keeps_its_steps_and_times() -> None:
    run = _man(TWO)
    run.call(5)
    t = run.st.t_ns[run.idx(11)]
    _place(run, 2)
    assert run.active == [2, 11]
    assert run.events(11) == set() and run.st.t_ns[run.idx(11)] > t  # not entered again


def test_several_steps_of_one_sequence_may_be_placed_together() -> None:
    run = _man(TWO)
    _place(run, 2, 12)
    assert run.active == [2, 12]
    _place(run, 1, 2)  # simultaneous in one sequence: both active
    assert run.active == [1, 2, 12]


def test_an_active_step_named_again_stays_without_events() -> None:
    run = _man(LINE)
    _place(run, 1)
    assert run.active == [1] and run.events(1) == set()


def test_moves_lists_what_leaves_and_what_enters() -> None:
    step_seq = (0, 0, 0, 1, 1)
    assert moves(step_seq, [0, 3], [2]) == ([0], [2])
    assert moves(step_seq, [0, 3], [0, 4]) == ([3], [4])
    assert moves(step_seq, [0], [0]) == ([], [])


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    start=st.sampled_from(STARTS),
    inputs=st.lists(st.binary(min_size=2, max_size=2), min_size=2, max_size=8),
    data=st.data(),
    man=st.booleans(),
)
def test_a_placement_at_a_random_moment_is_s_off_and_s_on_in_one_call(
    start: Path, inputs: list[bytes], data: st.DataObject, man: bool
) -> None:
    """A CPU runs a chart on random inputs (in MAN or not) and is placed at random steps:
    it scans as a fresh FB started from its state with the same placement, its active
    steps are the named ones where they belong and the others where they were, and a
    fresh FB moved there by S_OFF and S_ON, one step a call with the clock standing still,
    reaches the same steps with the same S0 and S1."""
    symbols = DRILL / "symbols.txt" if start.parent == DRILL else None
    model, table = _start(start, symbols)
    cc, table = compile_model(model, table)
    plant = ChartSession(cc, table, VirtualClock())
    plant.start()
    if man:
        plant.graph.command("SW_MAN")
    numbers = list(cc.step_numbers)
    for image in inputs[:-1]:
        plant.cpu.mem.periph_in[:2] = image
        plant.clock.advance(10)  # type: ignore[attr-defined]
        plant.scan()
    named = data.draw(st.lists(st.sampled_from(numbers), min_size=1, max_size=3), label="named")
    g = plant.graph
    before, in_man = set(g.state.active), g.state.mode == "MAN"
    leave, enter = moves(cc.step_seq, g.state.active, [cc.step_index[n] for n in named])
    # a step entered whose own ON/OFF row switches other steps (S11's ``S1 OFF S2``) makes
    # more moves than the placement: the chart's, not this property's
    assume(not _switches_steps(cc, [numbers[i] for i in enter]))
    plant.cpu.mem.periph_in[:2] = inputs[-1]
    # fresh FBs started from the plant's state (they share its clock): placed alike, not
    # placed, moved one step a call
    fresh, plain, stepped = twin(plant, []), twin(plant, []), twin(plant, [])
    fresh.graph.place(named)
    g.place(named)
    scan = _scan(plant)
    assert _scan(fresh) == scan
    if not in_man:
        assert _scan(plain) == scan  # outside MAN a placement does nothing
        return
    assert set(g.state.active) == (before - set(leave)) | set(enter)
    moved = [(step, event) for step, event, _ in scan.events if event in ("S0", "S1")]
    assert sorted(moved) == sorted(
        [(numbers[i], "S0") for i in leave] + [(numbers[i], "S1") for i in enter]
    )
    events = []
    for pin, i in [("S_OFF", i) for i in leave] + [("S_ON", i) for i in enter]:
        stepped.graph.command(pin, numbers[i])
        events += [(s, e) for s, e, _ in _scan(stepped).events if e in ("S0", "S1")]
    assert set(stepped.graph.state.active) == set(g.state.active)
    assert sorted(events) == sorted(moved)
    for image in inputs:  # the placed plant and its fresh twin go on alike
        plant.cpu.mem.periph_in[:2] = image
        fresh.cpu.mem.periph_in[:2] = image
        plant.clock.advance(10)  # type: ignore[attr-defined]
        assert _scan(fresh) == _scan(plant)


def _switches_steps(cc: CompiledChart, steps: list[int]) -> bool:
    """Whether one of ``steps`` has an ON or OFF action row (it switches other steps)."""
    return any(
        row.qualifier in ("ON", "OFF")
        for seq in cc.chart.sequences
        for step in seq.steps
        if step.number in steps
        for row in step.actions
        if hasattr(row, "qualifier")
    )
