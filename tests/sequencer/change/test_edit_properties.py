"""Properties of editing, over random sequences of edits from the operations table: every
edit keeps the chart valid or is refused with the chart unchanged, diagnostics are the
validator's, every diagnostic selects an element that exists, undo gives back the very
charts, renumbering there and back changes nothing."""

from __future__ import annotations

from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from s7graph.sequencer.change.content import RenumberStep
from s7graph.sequencer.change.edit import (
    OPERATIONS,
    Argument,
    Operation,
    Session,
    make_edit,
    new_chart,
)
from s7graph.sequencer.change.structure import DeleteStep, InsertStep
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.elements import element_of, find
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import unlocated
from tests.sequencer.helpers import CHARTS

STARTS = {
    "new": new_chart(),
    **{
        name: parse_chart((CHARTS / f"{name}.s7g").read_text(encoding="utf-8"), f"{name}.s7g")
        for name in ("linear", "alternative", "simultaneous", "stop", "two_sequencers")
    },
}

# Valid content only (no unknown operands, no step numbers): whatever an edit refuses, the
# charts it makes must compile. Invalid texts are in the pools too: they must be refused.
CONDITIONS = ["", "I0.0", "NOT I0.1 AND M0.0", "MW10 > 3 OR I0.2", "I0.0 AND", "I0.0; X"]
ROWS = [
    {"qualifier": "N", "operand": "Q0.0"},
    {"qualifier": "S", "operand": "Q0.1", "event": "S1"},
    {"qualifier": "D", "operand": "Q0.2", "value": "T#1S"},
    {"qualifier": "R", "operand": "Q0.1", "event": "S0"},
    {"qualifier": "N", "operand": "Q0.0; N Q0.1"},
    {"qualifier": "Q", "operand": "Q0.0"},
]
TEXTS: dict[str, list[Any]] = {
    "name": ["", "Clamp", "two\nlines"],
    "message": ["", "Work piece not clamped"],
    "condition": CONDITIONS,
    "option": ["SKIP_STEPS", "ORDER", "COLOUR"],
    "value": ["TRUE", "CODESYS", "MAYBE"],
    "text": [(CHARTS / "linear.s7g").read_text(encoding="utf-8"), "FUNCTION_BLOCK"],
}


def _numbers(c: Chart, name: str) -> list[int]:
    """The numbers an argument may name in ``c`` (mostly existing ones, and one spare)."""
    if name in ("transition", "join"):
        used = [t.number for t in c.all_transitions()]
    elif name == "sequence":
        used = [q.number for q in c.sequences]
    elif name in ("index", "at"):
        return [0, 1, 2, 3]
    else:
        used = [s.number for s in c.all_steps()]
    return [*used, max(used, default=0) + 1]


def _argument(c: Chart, a: Argument) -> st.SearchStrategy[Any]:
    if a.type == "RowFields":
        return st.sampled_from(ROWS)
    if a.type == "bool":
        return st.booleans()
    if a.type == "str":
        return st.sampled_from(TEXTS[a.name])
    numbers = st.sampled_from(_numbers(c, a.name))
    return st.one_of(st.none(), numbers) if a.type.endswith("None") else numbers


def _edit(data: st.DataObject, c: Chart) -> tuple[str, dict[str, Any]]:
    op: Operation = data.draw(st.sampled_from(OPERATIONS))
    return op.name, {a.name: data.draw(_argument(c, a)) for a in op.arguments}


@settings(max_examples=80, deadline=None)
@given(start=st.sampled_from(sorted(STARTS)), n=st.integers(0, 25), data=st.data())
def test_random_edits_keep_the_chart_valid_or_are_refused_and_undo_restores(
    start: str, n: int, data: st.DataObject
) -> None:
    first = Session.open(STARTS[start])
    assert not first.has_errors
    s = first
    for _ in range(n):
        before = s
        s = s.apply(make_edit(*_edit(data, s.chart)))
        if s.refusal is not None:
            assert s.chart is before.chart and s.done == before.done and s.refusal.reason
            continue
        assert s.diagnostics == tuple(validate(s.chart))
        assert not s.has_errors, [str(d.message) for d in s.diagnostics if d.is_error]
        for d in s.diagnostics:
            ref = element_of(d, s.chart)
            assert ref is not None and find(s.chart, ref) is not None, d
        if s.selection is not None:
            assert find(s.chart, s.selection) is not None
    last = s
    while s.done:
        s = s.undo()
    assert s.chart is first.chart and s.diagnostics == first.diagnostics
    while s.undone:
        s = s.redo()
    assert s.chart is last.chart


def _steps(c: Chart) -> list[int]:
    return [s.number for s in c.all_steps()]


@settings(max_examples=60, deadline=None)
@given(start=st.sampled_from(sorted(STARTS)), pick=st.integers(0, 20), to=st.integers(1, 99))
def test_renumbering_a_step_and_back_gives_the_chart_exactly(
    start: str, pick: int, to: int
) -> None:
    c = STARTS[start]
    n = _steps(c)[pick % len(_steps(c))]
    there = Session.open(c).apply(RenumberStep(n, to))
    if to in _steps(c) and to != n:
        assert there.refusal is not None
        return
    back = there.apply(RenumberStep(to, n))
    assert back.chart == c


@settings(max_examples=40, deadline=None)
@given(start=st.sampled_from(sorted(STARTS)), pick=st.integers(0, 20))
def test_deleting_a_step_inserted_after_any_transition_gives_the_chart_back(
    start: str, pick: int
) -> None:
    c = STARTS[start]
    t = c.all_transitions()[pick % len(c.all_transitions())]
    inserted = Session.open(c).apply(InsertStep(t.number))
    new = max(_steps(inserted.chart))
    assert unlocated(inserted.apply(DeleteStep(new)).chart) == unlocated(c)
