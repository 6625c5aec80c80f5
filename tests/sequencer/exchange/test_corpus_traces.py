"""The corpus charts that can run run as their origin runs them, checked through ``s7graph sim``
(docs/import-export.md). matiec's cycle (``generate_c_sfc.cc``) is GRAPH's order: the transitions
are tested on the state at the start of the call, then the steps switch, then the actions of the
active steps run, newly activated ones included; a D action becomes active in the call its step has
been active for its time. The FB's first call is OB100's (with INIT_SQ), before sim's cycle 0: it is
the origin's first cycle."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import import_file
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.model import Chart, Operand, VarDecl
from tests.sequencer.exchange.helpers import changes, corpus, import_to, scl_session, sim


def names(chart_path: Path) -> dict[str, str]:
    """Step label (S3) → the step's name, read from the imported chart."""
    chart = import_file(chart_path).chart
    return {f"S{s.number}": s.name for s in chart.all_steps()}


def step_names(records: list[dict], label: dict[str, str]) -> list[list[str]]:
    """The active steps by name, each time they change."""
    out: list[list[str]] = []
    for r in records:
        now = [label[s] for s in r["active"]]
        if not out or out[-1] != now:
            out.append(now)
    return out


# ---------------------------------------------------------------- matiec SFC_TEST

SFC_TEST_PATH = [
    ["STEP1"],  # GO → STEP1 at once (IX1 = FALSE), in cycle 0: the startup call holds GO
    ["STEP2"],  # IX2 from outside
    ["A1"],
    ["STEP2"],
    ["A2"],
    ["STEP2"],
    ["A3"],
    ["STEP2"],  # STEP2's P action toggles QX1, QX2
    ["D1", "D2", "D3"],
    ["E1", "E2", "E3"],  # simultaneous divergence, then the join
    ["GO"],  # and GO stays: A3 left IX1 TRUE, so IX1 = FALSE does not hold again
]


@pytest.mark.parametrize("relative", ["plcopen/matiec_SFC_TEST.xml", "iec-text/matiec_sfc.txt"])
def test_matiec_sfc_test_drives_itself_except_ix2(relative: str, tmp_path: Path) -> None:
    """SFC_TEST writes its own IX1 and QX1..QX3 (its located variables that an S7 CPU
    would overwrite or could not initialize are FB variables, reported); only IX2 (the
    symbol at I0.2) comes from outside. One round of its four-way alternative, one pass
    through the three-way branch and its join, back to GO."""
    source = corpus(relative)
    rc, chart = import_to(tmp_path, source)
    assert rc == 1
    label = names(source)
    idle = sim(tmp_path, chart, watch=["QX1", "IX1"], cycles=20)
    assert step_names(idle, label) == [["STEP1"]]
    records = sim(
        tmp_path,
        chart,
        watch=["QX1", "QX2", "QX3", "IX1", "IX2"],
        cycles=30,
        stimulus=[{"at_ms": 50, "set": {"IX2": True}}],
    )
    assert step_names(records, label) == SFC_TEST_PATH
    # GO is held by the startup call (an initial step is active for the call that activates
    # it, docs/semantics.md) and switches in cycle 0; IX2 at 50 ms lets STEP1 go.
    assert [r["t_ms"] for r in records if r["events"]][:2] == [0, 50]
    last = records[-1]["values"]
    assert last == {"QX1": True, "QX2": True, "QX3": True, "IX1": True, "IX2": True}


# ---------------------------------------------------------------- Beremiz first steps


def counter_st(reset: bool, cnt: int, reset_value: int = 17) -> int:
    """One call of CounterST of the same file: IF Reset THEN Cnt := ResetCounterValue
    ELSE Cnt := Cnt + 1; OUT := Cnt (ResetCounterValue is the configuration's 17)."""
    return reset_value if reset else cnt + 1


def test_first_steps_counter_sfc_counts_like_the_st_version(tmp_path: Path) -> None:
    """CounterSFC counts by CounterST's rule (as the FBD, IL and LD versions of the same
    file do), call by call, except in a call spent in its step Start, which has no action,
    so OUT keeps its value: the startup call (the initial step is active for the call that
    activates it, docs/semantics.md), and the one call after Reset changes (as in matiec,
    which switches at most one transition per path and call); a change in that very call
    takes Start's other way at once. Before the first change the chart gives the very same
    counts as CounterST, one call later."""
    rc, chart = import_to(tmp_path, corpus("plcopen/beremiz_first_steps.xml"))
    assert rc == 1  # the other POUs (the ST, FBD, IL, LD versions) are reported, not imported
    cycles = 40
    flips = {7: True, 12: False, 20: True, 21: False, 30: True, 35: False}
    stimulus = [{"at_ms": k * 10, "set": {"Reset": v}} for k, v in flips.items()]
    records = sim(tmp_path, chart, watch=["OUT", "Reset"], cycles=cycles, stimulus=stimulus)
    resets = [False] + [r["values"]["Reset"] for r in records]  # OB100's call comes first
    outs = [0] + [r["values"]["OUT"] for r in records]  # OB100's call: in Start, OUT stays 0
    st = [counter_st(False, 0)]
    in_start = True  # the startup call is spent in Start
    for k in range(1, cycles + 1):
        st.append(counter_st(resets[k], st[-1]))
        if resets[k] != resets[k - 1] and not in_start:
            assert outs[k] == outs[k - 1], k  # the call in Start
            in_start = True
        else:
            assert outs[k] == counter_st(resets[k], outs[k - 1]), k
            in_start = False
    assert outs[1:8] == st[:7] == list(range(1, 8))
    assert outs[9:13] == st[9:13] == [17, 17, 17, 17]


# ---------------------------------------------------------------- Beremiz traffic light

LIGHTS = [
    "RED_LIGHT",
    "ORANGE_LIGHT",
    "GREEN_LIGHT",
    "PEDESTRIAN_RED_LIGHT",
    "PEDESTRIAN_GREEN_LIGHT",
]


def traffic_light(tmp_path: Path, stimulus: list[dict], cycles: int) -> tuple[list[dict], dict]:
    source = corpus("plcopen/beremiz_traffic_light.xml")
    rc, chart = import_to(tmp_path, source)
    assert rc == 1
    records = sim(tmp_path, chart, watch=LIGHTS, cycles=cycles, cycle_ms=100, stimulus=stimulus)
    return records, names(source)


def test_traffic_light_cycles_through_its_d_timed_steps_until_stop(tmp_path: Path) -> None:
    """The file's task runs every 100 ms. With SWITCH_BUTTON on, each step's D action
    (2 s, 2 s, 10 s, 2 s, 20 s) becomes active after its time, and its transition switches
    in the next call; STOP (SWITCH_BUTTON off) jumps back to Standstill from any step, where
    BLINK_ORANGE_LIGHT blinks: its LD body's TON1/TON2 (500 ms) and R_TRIG0/R_TRIG1 run,
    600 ms a half period at 100 ms a call. Back after 50 s, TON2 (IN held TRUE since its
    last call, at 0 ms) is due at once: the P action's ORANGE_LIGHT := 1 is reset in the
    same call, as matiec's TON would reset it."""
    records, label = traffic_light(
        tmp_path,
        [
            {"at_ms": 0, "set": {"SWITCH_BUTTON": True}},
            {"at_ms": 50_000, "set": {"SWITCH_BUTTON": False}},
        ],
        520,
    )
    seen = [(t, [label[s] for s in active], lit) for t, active, lit in changes(records, *LIGHTS)]
    assert seen == [
        (0, ["ORANGE"], ["ORANGE_LIGHT", "PEDESTRIAN_RED_LIGHT"]),
        (2100, ["RED"], ["RED_LIGHT", "PEDESTRIAN_RED_LIGHT"]),
        (4200, ["PEDESTRIAN_GREEN"], ["RED_LIGHT", "PEDESTRIAN_GREEN_LIGHT"]),
        (14300, ["PEDESTRIAN_RED"], ["RED_LIGHT", "PEDESTRIAN_RED_LIGHT"]),
        (16400, ["GREEN"], ["GREEN_LIGHT", "PEDESTRIAN_RED_LIGHT"]),
        (36500, ["ORANGE"], ["ORANGE_LIGHT", "PEDESTRIAN_RED_LIGHT"]),
        (38600, ["RED"], ["RED_LIGHT", "PEDESTRIAN_RED_LIGHT"]),
        (40700, ["PEDESTRIAN_GREEN"], ["RED_LIGHT", "PEDESTRIAN_GREEN_LIGHT"]),
        (50000, ["Standstill"], []),
        (50600, ["Standstill"], ["ORANGE_LIGHT"]),
        (51200, ["Standstill"], []),
        (51800, ["Standstill"], ["ORANGE_LIGHT"]),
    ]


def test_traffic_light_pedestrian_button_cuts_green_short_through_its_chart_blocks(
    tmp_path: Path,
) -> None:
    """The blocks drawn in the chart (SR0 set by PEDESTRIAN_BUTTON, reset by TON3, which it
    starts) run every call, as Beremiz's COMPUTE_FUNCTION_BLOCKS does: a press in GREEN
    leads to ORANGE 2 s later (TON3.Q), not after WARN_CARS' 20 s."""
    records, label = traffic_light(
        tmp_path,
        [
            {"at_ms": 0, "set": {"SWITCH_BUTTON": True}},
            {"at_ms": 20_000, "set": {"PEDESTRIAN_BUTTON": True}},
            {"at_ms": 20_300, "set": {"PEDESTRIAN_BUTTON": False}},
        ],
        260,
    )
    seen = [(t, [label[s] for s in active]) for t, active, _ in changes(records)]
    assert seen[4:6] == [(16400, ["GREEN"]), (22100, ["ORANGE"])]


def test_traffic_light_alternative_without_priority_takes_the_left_path(tmp_path: Path) -> None:
    """Beremiz draws ORANGE's alternative without priorities: when STOP and STOP_CARS hold
    in the same call, matiec switches both paths (Standstill and RED both active). GRAPH
    switches exactly one, the leftmost (STOP at x=405 before STOP_CARS at x=559): the
    import writes them in that order, and the GRAPH rule applies."""
    records, label = traffic_light(
        tmp_path,
        [
            {"at_ms": 0, "set": {"SWITCH_BUTTON": True}},
            {"at_ms": 2100, "set": {"SWITCH_BUTTON": False}},
        ],
        25,
    )
    at = next(r for r in records if r["t_ms"] == 2100)
    assert [label[s] for s in at["active"]] == ["Standstill"]


# ---------------------------------------------------------------- TIA exports


def tia(tmp_path: Path, name: str) -> tuple[Path, Chart]:
    source = corpus(f"simaticml/{name}.xml")
    rc, chart_path = import_to(tmp_path, source)
    assert rc in (0, 1)
    return chart_path, import_file(source).chart


def with_switches(chart: Chart, tmp_path: Path) -> Path:
    """The chart with each transition's condition replaced by an FB variable ``go<n>``."""
    seqs = tuple(
        dataclasses.replace(
            q,
            transitions=tuple(
                dataclasses.replace(t, condition=Operand(f"go{t.number}")) for t in q.transitions
            ),
        )
        for q in chart.sequences
    )
    decls = tuple(VarDecl(f"go{t.number}", "BOOL") for t in chart.all_transitions())
    path = tmp_path / "switches.s7g"
    path.write_text(format_chart(dataclasses.replace(chart, sequences=seqs, vars=decls)))
    return path


def test_tia_empty_transitions_run_the_first_path_of_each_branch(tmp_path: Path) -> None:
    """An empty TIA transition (its coil on the power rail) holds: the chain switches once a
    call (the initial step S1 is held by the startup call that activates it, so it leaves in
    cycle 0), and at each alternative branch the first path (Out 0) wins; T43 jumps back."""
    chart_path, _ = tia(tmp_path, "GraphBranch2")
    records = sim(tmp_path, chart_path, watch=[], cycles=6)
    assert [r["events"] for r in records] == [
        [["S1", "S21"]],
        [["S21", "S27"]],
        [["S27", "S32"]],
        [["S32", "S43"]],
        [["S43", "S1"]],
        [["S1", "S21"]],
    ]


def test_tia_alternative_paths_jump_where_the_xml_says(tmp_path: Path) -> None:
    """GraphBranchAbortOption: S21's branch has three paths — T21 to S27, T121 jumping to
    S32, T221 jumping to S43; with only the second or third enabled, the chain jumps."""
    _, chart = tia(tmp_path, "GraphBranchAbortOption")
    path = with_switches(chart, tmp_path)
    enable = {"go1": True, "go27": True, "go32": True, "go43": True}
    for go, expected in (("go121", ["S21", "S32"]), ("go221", ["S21", "S43"])):
        records = sim(
            tmp_path, path, watch=[], cycles=4, stimulus=[{"at_ms": 0, "set": {**enable, go: True}}]
        )
        events = [e for r in records for e in r["events"]]
        assert events[:2] == [["S1", "S21"], expected]


def test_tia_branch_stop_ends_the_chain(tmp_path: Path) -> None:
    chart_path, _ = tia(tmp_path, "GraphEnd")
    records = sim(tmp_path, chart_path, watch=[], cycles=5)
    assert [r["events"] for r in records][:4] == [
        [["S1", "S21"]],
        [["S21", "S32"]],
        [["S32", "S43"]],
        [["S43", "STOP"]],
    ]
    assert records[-1]["active"] == []


def test_tia_v16_sequence_switches_on_its_lad_condition_and_stops(tmp_path: Path) -> None:
    """StepSequence: Trans1 (CylcleState = 1 AND StepMode = 0 AND CurrentTime > WaitingTime,
    or single step) leads to Step2, whose N row writes CurrentStep := 2; Trans2 ends it."""
    chart_path, _ = tia(tmp_path, "StepSequence")
    watch = ['"StepData.Values.CurrentStep"']
    tags = {
        "StepData.Values.CylcleState": 1,
        "StepData.Values.StepMode": 0,
        "StepData.Values.CurrentTime": 5,
    }
    records = sim(
        tmp_path, chart_path, watch=watch, cycles=6, stimulus=[{"at_ms": 20, "set": tags}]
    )
    assert [r["values"][watch[0]] for r in records[:2]] == [1, 1]
    assert records[2]["events"] == [["S1", "S2"]] and records[2]["values"][watch[0]] == 2
    assert records[3]["events"] == [["S2", "STOP"]]


# ---------------------------------------------------------------- no silent stalls

# file → a stimulus (at 0 ms) under which every initial step with a way out takes it
LEAVES: dict[str, dict[str, object]] = {
    "plcopen/beremiz_first_steps.xml": {},
    "plcopen/beremiz_test_svgui.xml": {"CNT2": True},
    "plcopen/beremiz_traffic_light.xml": {"SWITCH_BUTTON": True},
    "plcopen/iec_checker_example.xml": {"IN1": True, "IN2": True, "IN3": True},
    "plcopen/matiec_SFC_TEST.xml": {},
    "iec-text/ironplc_first_steps_counter_sfc.st": {},
    "iec-text/matiec_annexF_gravel.txt": {"ON_PB": True, "FILL_PB": True},
    "iec-text/matiec_sfc.txt": {},
    "simaticml/GraphBranch2.xml": {},
    "simaticml/GraphBranchAbortOption.xml": {},
    "simaticml/GraphEnd.xml": {},
    "simaticml/StepSequence.xml": {
        "StepData.Values.CylcleState": 1,
        "StepData.Values.StepMode": 0,
        "StepData.Values.CurrentTime": 5,
    },
}


@pytest.mark.parametrize("relative", sorted(LEAVES))
def test_every_corpus_chart_leaves_its_initial_steps_or_the_import_says_why(
    relative: str, tmp_path: Path
) -> None:
    """No corpus chart is stuck in an initial step without the import saying so (I025, with
    the reason): none is stuck, and under a plain stimulus of its inputs each initial step
    that has a way out takes it."""
    source = corpus(relative)
    result = import_file(source)
    assert [d for d in result.problems if d.code == "I025"] == []
    rc, chart = import_to(tmp_path, source)
    assert rc in (0, 1)
    leaving = {f"S{s}" for t in result.chart.all_transitions() for s in t.sources}
    initial = {f"S{s.number}" for s in result.chart.all_steps() if s.initial} & leaving
    if result.functions:  # the chart calls the SCL FCs of its ST bodies: run them with it
        assert chart.with_suffix(".scl").read_text(encoding="utf-8") == result.blocks_scl
        session = scl_session(result)
        for name, value in LEAVES[relative].items():
            session.set(name, value)
        left: set[str] = set()
        for _ in range(40):
            session.clock.advance(10)  # type: ignore[attr-defined]
            session.scan()
            left |= {s for s in initial if not session.get(f"{s}.X")}
        assert initial <= left, initial - left
        return
    stimulus = [{"at_ms": 0, "set": LEAVES[relative]}] if LEAVES[relative] else []
    records = sim(tmp_path, chart, watch=[], cycles=40, stimulus=stimulus)
    left = {e[0] for r in records for e in r["events"]}
    assert initial <= left, (initial - left, records[-1]["active"])
