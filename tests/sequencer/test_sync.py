"""Synchronization (docs/semantics.md, "Synchronization"): a step fits the process when its
interlock holds and none of its leaving transitions does; it is likely when a transition
into it holds too. Judged on the current values whatever the steps' activity, without
writing anything: a CPU judged between random scans scans as one never judged."""

from __future__ import annotations

import copy
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from s7graph.engine.clock import VirtualClock
from s7graph.sequencer.sync import SyncStep, synchronization
from s7graph.web.harness.session import ChartSession, compile_model
from tests.sequencer.change.test_online_change_properties import DRILL, STARTS, _scan, _start
from tests.sequencer.helpers import Run, chart, seq

LINE = seq("""
  INITIAL_STEP S1 "Ready": END_STEP
  STEP S2 "Clamp": INTERLOCK := I1.0; N Q0.0; END_STEP
  STEP S3 "Drill": N Q0.1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
  TRANSITION T3 FROM S3 TO S1 := I0.2;
""")


def _judge(run: Run) -> dict[int, SyncStep]:
    return {s.number: s for s in synchronization(run.cc, run.rt.prog, run.st)}


def test_a_step_fits_when_its_interlock_holds_and_no_leaving_transition_does() -> None:
    run = chart(LINE)
    run.call()
    # the clamp is closed (T1's start signal still on), the drill not yet down
    run.set(I0_0=True, I1_0=True)
    steps = _judge(run)
    assert steps[1].done == (1,) and not steps[1].fits  # S1's work is done
    assert steps[2].fits and steps[2].entered and steps[2].likely
    assert steps[3].fits and not steps[3].entered and not steps[3].likely
    assert [s.number for s in steps.values() if s.likely] == [2]


def test_a_step_whose_interlock_does_not_hold_does_not_fit() -> None:
    run = chart(LINE)
    run.call()
    run.set(I0_0=True, I1_0=False)
    steps = _judge(run)
    assert not steps[2].interlock and not steps[2].fits and not steps[2].likely


def test_a_step_whose_leaving_transition_holds_is_done() -> None:
    run = chart(LINE)
    run.call()
    run.set(I0_1=True, I1_0=True)
    steps = _judge(run)
    assert steps[2].done == (2,) and not steps[2].fits
    assert steps[3].likely  # T2 into it holds, T3 out of it does not


def test_inactive_steps_are_judged_and_the_active_ones_are_marked() -> None:
    run = chart(LINE)
    run.call()
    steps = _judge(run)
    assert [s.number for s in steps.values() if s.active] == [1]
    assert {s.number: s.name for s in steps.values()} == {1: "Ready", 2: "Clamp", 3: "Drill"}
    assert {s.sequence for s in steps.values()} == {1}


def test_a_step_no_transition_leads_to_counts_as_entered() -> None:
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO STOP := I0.1;
    """)
    )
    run.call()
    steps = _judge(run)
    assert steps[1].entered and steps[1].likely
    assert not steps[2].entered and steps[2].fits


def test_alternative_branches_list_every_leaving_transition_that_holds() -> None:
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S1 TO S3 := I0.1;
      TRANSITION T3 FROM S2 TO S1 := I0.2;
      TRANSITION T4 FROM S3 TO S1 := I0.3;
    """)
    )
    run.call()
    run.set(I0_0=True, I0_1=True)
    steps = _judge(run)
    assert steps[1].done == (1, 2)
    assert steps[2].likely and steps[3].likely


def test_judging_writes_nothing() -> None:
    run = chart(LINE)
    run.call()
    run.set(I0_0=True, I1_0=False, I0_2=True)
    run.call()  # T1 switches: S2 active, its interlock lost
    before = copy.deepcopy(run.st)
    image = bytes(run.mem.outputs), bytes(run.mem.markers)
    _judge(run)
    assert run.st == before
    assert (bytes(run.mem.outputs), bytes(run.mem.markers)) == image


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    start=st.sampled_from(STARTS),
    inputs=st.lists(st.binary(min_size=2, max_size=2), min_size=1, max_size=10),
    judged=st.sets(st.integers(0, 9)),
    ms=st.sampled_from([10, 250, 1200]),
)
def test_judging_between_scans_leaves_the_plant_scanning_as_one_never_judged(
    start: Path, inputs: list[bytes], judged: set[int], ms: int
) -> None:
    """Two CPUs run the same chart on the same inputs; one is judged between some scans:
    both scan alike, judging twice gives the same, and every verdict follows its rule."""
    symbols = DRILL / "symbols.txt" if start.parent == DRILL else None
    chart, table = _start(start, symbols)
    cc, table = compile_model(chart, table)
    plants = [ChartSession(cc, table, VirtualClock()) for _ in range(2)]
    for plant in plants:
        plant.start()
    judged_one, fresh = plants
    for k, data in enumerate(inputs):
        for plant in plants:
            plant.cpu.mem.periph_in[:2] = data
            plant.clock.advance(ms)  # type: ignore[attr-defined]
        if k in judged:
            graph, mem = judged_one.graph, judged_one.cpu.mem
            before = graph.state.to_state(), bytes(mem.inputs), bytes(mem.markers)
            steps = graph.synchronization()
            assert (graph.state.to_state(), bytes(mem.inputs), bytes(mem.markers)) == before
            assert graph.synchronization() == steps
            for s in steps:
                assert s.fits == (s.interlock and not s.done)
                assert s.likely == (s.fits and s.entered)
        assert _scan(judged_one) == _scan(fresh)
