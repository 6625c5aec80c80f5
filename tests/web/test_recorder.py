"""The rerun recorder: a run becomes a .rrd timeline that reads back step by step."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.bus.protocol import ChartLayout, StepStateUpdate
from s7graph.web.recorder import Recorder, available

pytestmark = [
    pytest.mark.timeout(60),
    pytest.mark.skipif(not available(), reason="rerun-sdk not importable (extra [trace])"),
]


def layout() -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run", supervision=None))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)))


def run() -> list[StepStateUpdate]:
    """Ten scans: S1 for cycles 0-4, S2 for 5-9; a supervision error on S2 at cycle 7."""
    scans = []
    for c in range(10):
        events: list[tuple[str, int]] = []
        if c == 5:
            events = [("S0", 1), ("S1", 2)]
        if c == 7:
            events = [("V1", 2)]
        scans.append(
            StepStateUpdate(
                cycle=c,
                t_ms=c * 10,
                mode="AUTO" if c < 8 else "MAN",
                active=[1] if c < 5 else [2],
                events=events,  # type: ignore[arg-type]
                values={"level": float(c), "label": "text is skipped"},
            )
        )
    return scans


def chunks_by_entity(path: Path) -> dict[str, list]:
    from rerun.chunk import RrdReader

    found: dict[str, list] = {}
    for chunk in RrdReader(str(path)).stream().to_chunks():
        if not chunk.is_static:
            found.setdefault(chunk.entity_path, []).append(chunk.to_record_batch())
    return found


def column(batches: list, name: str) -> list:
    return [v for rb in batches for v in rb.column(name).to_pylist()]


def test_step_activity_is_a_scalar_timeline_on_the_cycle_axis(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    with Recorder(layout(), path) as recorder:
        for update in run():
            recorder.record(update)
    found = chunks_by_entity(path)
    s1 = found["/s7graph/FILL/step/S1"]
    assert column(s1, "cycle") == [0, 5]  # logged on change only
    assert column(s1, "Scalars:scalars") == [[1.0], [0.0]]
    s2 = found["/s7graph/FILL/step/S2"]
    assert list(zip(column(s2, "cycle"), column(s2, "Scalars:scalars"), strict=True)) == [
        (0, [0.0]),
        (5, [1.0]),
    ]
    assert len(column(found["/s7graph/FILL/value/level"], "cycle")) == 10


def test_events_and_mode_changes_are_a_text_log_with_errors_marked(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    with Recorder(layout(), path) as recorder:
        for update in run():
            recorder.record(update)
    events = chunks_by_entity(path)["/s7graph/FILL/events"]
    texts = [t for (t,) in column(events, "TextLog:text")]
    levels = [lv for (lv,) in column(events, "TextLog:level")]
    assert texts == ["S0 S1", "S1 S2", "V1 S2", "mode AUTO -> MAN"]
    assert levels[texts.index("V1 S2")] == "ERROR"


def test_a_memory_recording_returns_rrd_bytes() -> None:
    recorder = Recorder(layout())
    for update in run()[:3]:
        recorder.record(update)
    data = recorder.close()
    assert data is not None and data.startswith(b"RRF2") and len(data) > 1000


def test_after_an_online_change_the_new_chart_s_steps_are_recorded(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    steps = (Step(1, "Idle", initial=True), Step(3, "New"), Step(2, "Run"))
    transitions = (
        Transition(1, "", (1,), (3,)),
        Transition(3, "", (3,), (2,)),
        Transition(2, "", (2,), (1,)),
    )
    inserted = ChartLayout.from_chart(
        Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)), version=2
    )
    with Recorder(layout(), path) as recorder:
        recorder.record(StepStateUpdate(cycle=0, t_ms=0, mode="AUTO", active=[1]))
        recorder.chart_changed(inserted)  # S3 inserted between S1 and S2
        recorder.record(
            StepStateUpdate(cycle=1, t_ms=10, mode="AUTO", active=[3], events=[("S1", 3)])  # type: ignore[list-item]
        )
    s3 = chunks_by_entity(path)["/s7graph/FILL/step/S3"]
    assert column(s3, "cycle") == [1] and column(s3, "Scalars:scalars") == [[1.0]]
