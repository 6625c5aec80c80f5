"""What a scan costs the bus: step details built only for the steps whose state changed,
the scan's events grouped once for every LiveGraph of a CPU — and the messages exactly
what they were (a LiveGraph that builds everything afresh agrees, scan after scan)."""

from __future__ import annotations

import random
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, StepEvent, install_all
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import EVENTS, StepStateUpdate
from s7graph.web.bus.scan_events import ScanEvents
from s7graph.web.bus.step_details import StepDetails
from s7graph.web.harness.session import ChartSession
from tests.web.helpers import chart_session

SEQUENCES = 4


def toggles_chart() -> str:
    """Four sequences, each S(2k-1) ⇄ S(2k) on its input "Gk"; S(2k) with an interlock
    on "Ik" and a supervision on "Vk", so every kind of contact is there."""
    symbols = [f'  "G{k}" : I0.{k - 1} : BOOL;' for k in range(1, SEQUENCES + 1)]
    symbols += [f'  "I{k}" : I1.{k - 1} : BOOL;' for k in range(1, SEQUENCES + 1)]
    symbols += [f'  "V{k}" : I2.{k - 1} : BOOL;' for k in range(1, SEQUENCES + 1)]
    out = [
        'FUNCTION_BLOCK "Toggles" FB 1 DB 1',
        "  PARAMETERS := STANDARD;",
        "  ACK_REQUIRED := FALSE;",
        "SYMBOLS",
        *symbols,
        "END_SYMBOLS",
    ]
    for k in range(1, SEQUENCES + 1):
        a, b = 2 * k - 1, 2 * k
        out += [
            f'SEQUENCE {k} "Seq{k}"',
            f'  INITIAL_STEP S{a} "Off{k}":',
            "  END_STEP",
            f'  STEP S{b} "On{k}":',
            f'    INTERLOCK := "I{k}";',
            f'    SUPERVISION := "V{k}";',
            "  END_STEP",
            f'  TRANSITION T{a} FROM S{a} TO S{b} := "G{k}" AND NOT "V{k}";',
            f'  TRANSITION T{b} FROM S{b} TO S{a} := NOT "G{k}";',
            "END_SEQUENCE",
        ]
    out.append("END_FUNCTION_BLOCK")
    return "\n".join(out) + "\n"


@pytest.fixture
def toggles(tmp_path: Path) -> Iterator[tuple[ChartSession, VirtualClock, LiveGraph]]:
    session, _, clock, store = chart_session(tmp_path, "toggles.s7g", toggles_chart())
    live = LiveGraph(session.graph)
    session.start()
    try:
        yield session, clock, live
    finally:
        store.close()


def scan(
    session: ChartSession, clock: VirtualClock, live: LiveGraph, ms: float = 1.0
) -> StepStateUpdate:
    clock.advance(ms)
    return live.update(session.scan())


def test_a_scan_that_changes_nothing_builds_no_detail(
    toggles: tuple[ChartSession, VirtualClock, LiveGraph],
) -> None:
    session, clock, live = toggles
    first = scan(session, clock, live, 10)
    built = live.step_details.built
    assert built == SEQUENCES  # one per active step
    for _ in range(20):  # 1 ms scans: the times stay within their tenth of a second
        later = scan(session, clock, live)
        assert all(a is b for a, b in zip(later.details, first.details, strict=True))
    assert live.step_details.built == built


def test_a_switching_step_gets_a_new_detail_and_the_others_keep_theirs(
    toggles: tuple[ChartSession, VirtualClock, LiveGraph],
) -> None:
    session, clock, live = toggles
    before = scan(session, clock, live, 10)
    built = live.step_details.built
    session.set("G2", True)
    after = scan(session, clock, live)
    assert after.active == [1, 4, 5, 7]
    assert live.step_details.built == built + 1  # S4 entered; S3's detail is gone
    kept = {d.number: d for d in before.details}
    for d in after.details:
        if d.number != 4:
            assert d is kept[d.number]
    session.set("I2", True)  # S4's interlock now holds: that step alone changes
    scan(session, clock, live)
    assert live.step_details.built == built + 2


def test_step_times_make_a_new_detail_each_tenth_of_a_second(
    toggles: tuple[ChartSession, VirtualClock, LiveGraph],
) -> None:
    session, clock, live = toggles
    scan(session, clock, live, 10)
    built = live.step_details.built
    for _ in range(10):
        scan(session, clock, live, 10)  # 100 ms: every active step's T and U moved on
    assert live.step_details.built == built + SEQUENCES
    assert [d.t_ms for d in live.details()] == [100] * SEQUENCES


def test_details_built_once_are_those_a_fresh_view_builds(
    toggles: tuple[ChartSession, VirtualClock, LiveGraph],
) -> None:
    """Random inputs for 400 scans: the reused details equal those built from scratch."""
    session, clock, live = toggles
    rng = random.Random(12)
    names = [f"{p}{k}" for p in "GIV" for k in range(1, SEQUENCES + 1)]
    for n in range(400):
        if rng.random() < 0.3:
            name = rng.choice(names)
            session.set(name, not session.get(name))
        update = scan(session, clock, live, rng.choice((1, 10, 40)))
        fresh = LiveGraph(session.graph)
        assert update.details == fresh.details(), f"scan {n}"
    assert live.step_details.built < 400 * SEQUENCES / 2


FB_TEXT = """\
FUNCTION_BLOCK "Loop{n}" FB {n} DB {n}
VAR
  cnt : INT := 0;
END_VAR
SEQUENCE 1 "Loop"
  INITIAL_STEP S1 "a":
    S1 N cnt := 0;  N cnt := cnt + 1;
  END_STEP
  STEP S2 "b":
    S1 N cnt := 0;  N cnt := cnt + 1;
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := cnt >= {p};
  TRANSITION T2 FROM S2 TO S1 := cnt >= {p};
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_the_events_of_a_scan_are_grouped_once_for_every_fb_of_the_cpu() -> None:
    clock = VirtualClock()
    cpu = Cpu(clock)
    fbs = [
        GraphFB(compile_chart(parse_chart(FB_TEXT.format(n=n, p=n + 1), f"<loop {n}>")))
        for n in (1, 2, 3)
    ]
    install_all(cpu, fbs)
    cpu.start("warm")
    events = ScanEvents()
    lives = [LiveGraph(g, events=events) for g in fbs]
    for k in range(1, 13):
        clock.advance(10)
        record = cpu.scan()
        updates = [live.update(record) for live in lives]
        assert events.groupings == k  # one walk of the record for the three FBs
        for g, update in zip(fbs, updates, strict=True):
            own = [
                (e.event, e.step)
                for e in record.events
                if isinstance(e, StepEvent) and e.db == g.db_number and e.event in EVENTS
            ]
            assert update.events == own
    assert any(u.events for u in updates)


def test_a_chart_without_interlocks_keys_its_details_by_times_and_transitions_alone() -> None:
    """A divergence and a join: the lean keys give the details the full keys give."""
    text = """\
FUNCTION_BLOCK "Join" FB 1 DB 1
SEQUENCE 1 "A"
  INITIAL_STEP S1 "a":
  END_STEP
  STEP S2 "b":
  END_STEP
  STEP S3 "c":
  END_STEP
  STEP S4 "d":
  END_STEP
  TRANSITION T1 FROM S1 TO (S2, S3) := S1.T >= T#30MS;
  TRANSITION T2 FROM S2 TO S4 := S2.T >= T#50MS;
  TRANSITION T3 FROM (S4, S3) TO S1 := S3.T >= T#150MS;
  TRANSITION T4 FROM S3 TO S1 := S3.T >= T#1S AND S2.X;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    clock = VirtualClock()
    cpu = Cpu(clock)
    g = GraphFB(compile_chart(parse_chart(text, "<join>")))
    install_all(cpu, [g])
    cpu.start("warm")
    live = LiveGraph(g)
    lean = live.step_details
    assert not lean.checks
    full = LiveGraph(g).prepare(g.cc, version=1)
    keyed = StepDetails(full.cc, full.tr_neg, full.il_neg, full.sv_neg, checks=True)
    rng = random.Random(3)
    for n in range(300):
        clock.advance(rng.choice((1, 10, 40, 120)))
        cpu.scan()
        assert lean.of(g.state) == keyed.of(g.state), f"scan {n}"
    assert lean.built < 300
