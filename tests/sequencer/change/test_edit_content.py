"""Editing what a step, transition, row or the header holds (``sequencer.change.content``):
every edit gives a chart the validator checks, or a refusal naming the problem."""

from __future__ import annotations

import pytest

from s7graph.sequencer.change.content import (
    AddRow,
    ChangeRow,
    MoveRow,
    RemoveRow,
    RenameStep,
    RenumberStep,
    RenumberTransition,
    SetCondition,
    SetInitial,
    SetInterlock,
    SetMessage,
    SetOption,
    SetSource,
    SetSupervision,
)
from s7graph.sequencer.change.edit import Session, apply_edit, make_edit
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.elements import RowRef, StepRef, TransitionRef, references
from s7graph.sequencer.text.model import Chart, Operand, StepTarget
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import unlocated
from tests.sequencer.helpers import CHARTS, seq, source

# S3 is named everywhere a step can be: FROM/TO, ON/OFF rows, Sn.X/T/U in conditions,
# in a row's assignment and in a permanent instruction; T2 by T2.TT.
REFERENCED = source(
    seq(
        "INITIAL_STEP S1: S1 ON S3; END_STEP\n"
        "STEP S2: SUPERVISION := S3.T > T#2S; S1 N n := n + 1; S0 OFF S3; END_STEP\n"
        "STEP S3: INTERLOCK := NOT S2.X; N C Q0.0; END_STEP\n"
        "TRANSITION T1 FROM S1 TO S2 := I0.0;\n"
        "TRANSITION T2 FROM S2 TO S3 := S3.U < T#1S OR T2.TT;\n"
        "TRANSITION T3 FROM S3 TO S1 := T2.TT AND S3.X;\n"
    ),
    header="VAR n : INT; END_VAR\nPERMANENT AFTER M0.0 := S3.X; END_PERMANENT",
)


def chart(text: str = REFERENCED) -> Chart:
    return parse_chart(text, "t.s7g")


def made(c: Chart, edit: object) -> Chart:
    out = apply_edit(c, edit)  # type: ignore[arg-type]
    assert out.refusal is None, out.refusal
    return out.chart


def refused(c: Chart, edit: object) -> str:
    out = apply_edit(c, edit)  # type: ignore[arg-type]
    assert out.refusal is not None and out.chart is c
    return out.refusal.reason


def named(c: Chart, kind: type, n: int) -> int:
    return sum(1 for _, r in references(c) if isinstance(r, kind) and r.number == n)


# ---------------------------------------------------------------- steps


def test_a_referenced_chart_is_clean_before_any_edit() -> None:
    assert validate(chart()) == []


def test_renaming_a_step_keeps_its_number_and_selects_it() -> None:
    out = apply_edit(chart(), RenameStep(2, "Clamp work piece"))
    assert out.selection == StepRef(2)
    assert [s.name for s in out.chart.all_steps()] == ["", "Clamp work piece", ""]


def test_renumbering_a_step_rewrites_every_reference_to_it() -> None:
    before = chart()
    after = made(before, RenumberStep(3, 9))
    assert named(after, StepRef, 3) == 0
    assert named(after, StepRef, 9) == named(before, StepRef, 3) == 8
    assert [s.number for s in after.all_steps()] == [1, 2, 9]
    assert validate(after) == []


def test_renumbering_a_step_and_back_gives_the_chart_exactly() -> None:
    before = chart()
    assert made(made(before, RenumberStep(3, 40)), RenumberStep(40, 3)) == before


def test_renumbering_a_step_to_a_number_in_use_or_out_of_range_is_refused() -> None:
    assert "S1 exists already" in refused(chart(), RenumberStep(3, 1))
    assert "out of range 1..32767" in refused(chart(), RenumberStep(3, 0))
    assert "out of range" in refused(chart(), RenumberStep(3, 10**30))


def test_renumbering_a_transition_rewrites_its_TT_operands() -> None:
    after = made(chart(), RenumberTransition(2, 7))
    assert named(after, TransitionRef, 2) == 0 and named(after, TransitionRef, 7) == 2
    assert validate(after) == []


def test_initial_flag_and_message_text_are_set() -> None:
    c = made(made(chart(), SetInitial(2, True)), SetMessage(2, "Work piece not clamped"))
    s2 = c.all_steps()[1]
    assert (s2.initial, s2.message) == (True, "Work piece not clamped")
    assert not made(c, SetInitial(2, False)).all_steps()[1].initial


def test_a_name_with_a_line_break_or_too_long_is_refused() -> None:
    assert "line break" in refused(chart(), RenameStep(2, "two\nlines"))
    assert "at most 128" in refused(chart(), RenameStep(2, "x" * 129))
    assert "there is no step S8" in refused(chart(), RenameStep(8, "x"))


# ---------------------------------------------------------------- conditions


def test_a_condition_means_what_it_means_in_a_file() -> None:
    text = '"Start" AND NOT S2.X OR MW10 > 3'
    edited = made(chart(), SetCondition(1, text))
    in_file = chart(REFERENCED.replace("TO S2 := I0.0", f"TO S2 := {text}"))
    assert unlocated(edited) == unlocated(in_file)


def test_a_condition_carries_places_in_its_own_text() -> None:
    edited = made(chart(), SetCondition(1, "I0.0 AND MX0.9"))
    d = next(d for d in validate(edited) if d.code == "E041")
    assert (d.loc.file, d.loc.line, d.loc.col, d.element) == (
        "<condition>",
        1,
        10,
        "transition T1",
    )


def test_a_syntax_error_in_a_condition_is_refused_with_its_column_in_the_condition() -> None:
    out = apply_edit(chart(), SetCondition(1, "I0.0 AND )"))
    assert out.refusal is not None
    (d,) = out.refusal.diagnostics
    assert (d.code, d.loc.file, d.loc.line, d.loc.col) == ("E001", "<condition>", 1, 10)
    assert "line 1, column 10" in out.refusal.reason


def test_a_condition_that_ends_too_early_is_located_at_its_end() -> None:
    out = apply_edit(chart(), SetCondition(1, "I0.0 AND\nI0.1 OR"))
    assert out.refusal is not None
    (d,) = out.refusal.diagnostics
    assert (d.loc.line, d.loc.col) == (2, 8)
    assert d.message.startswith("the text ends too early")


def test_a_condition_text_holding_more_than_a_condition_is_refused() -> None:
    reason = refused(chart(), SetCondition(1, "I0.0; TRANSITION T9 FROM S1 TO S1 := I0.1"))
    assert "more than one condition" in reason


def test_a_line_comment_may_end_a_condition() -> None:
    edited = made(chart(), SetCondition(1, "I0.0 // the start button"))
    cond = edited.all_transitions()[0].condition
    assert isinstance(cond, Operand) and cond.name == "I0.0"


def test_an_empty_condition_leaves_the_transition_empty_and_warns_W120() -> None:
    out = apply_edit(chart(), SetCondition(1, "  "))
    assert out.chart.all_transitions()[0].condition is None
    assert [(d.code, d.element) for d in out.diagnostics] == [("W120", "transition T1")]


def test_an_unknown_symbol_is_kept_and_listed_for_its_transition() -> None:
    out = apply_edit(chart(), SetCondition(3, '"Nowhere"'))
    assert out.made
    assert [(d.code, d.element) for d in out.diagnostics] == [("E040", "transition T3")]


def test_interlock_and_supervision_are_set_and_removed() -> None:
    c = made(chart(), SetInterlock(1, "I1.0"))
    c = made(c, SetSupervision(1, "S1.U > T#5S"))
    s1 = c.all_steps()[0]
    assert s1.interlock is not None and s1.supervision is not None
    assert validate(c) == []
    c = made(made(c, SetInterlock(1, "")), SetSupervision(1, ""))
    assert (c.all_steps()[0].interlock, c.all_steps()[0].supervision) == (None, None)


def test_removing_the_interlock_of_a_step_with_C_rows_warns_W122() -> None:
    out = apply_edit(chart(), SetInterlock(3, ""))
    assert [(d.code, d.element) for d in out.diagnostics] == [("W122", "step S3 row 1")]


# ---------------------------------------------------------------- action rows


def test_rows_are_added_changed_moved_and_removed() -> None:
    c = made(chart(), AddRow(3, RowFields("D", "Q0.4", value="T#2S")))
    c = made(c, AddRow(3, RowFields("S", '"Clamp"', event="S1"), at=0))
    rows = c.all_steps()[2].actions
    assert [(r.event, r.qualifier) for r in rows] == [("S1", "S"), (None, "N"), (None, "D")]
    c = made(c, ChangeRow(3, 0, RowFields("R", '"Clamp"', event="S0")))
    c = made(c, MoveRow(3, 0, 2))
    assert [r.qualifier for r in c.all_steps()[2].actions] == ["N", "D", "R"]
    c = made(c, RemoveRow(3, 1))
    assert [r.qualifier for r in c.all_steps()[2].actions] == ["N", "R"]


def test_adding_a_row_selects_it() -> None:
    out = apply_edit(chart(), AddRow(1, RowFields("N", "Q1.0")))
    assert out.selection == RowRef(1, 1)


def test_a_row_names_its_step_for_ON_and_OFF() -> None:
    c = made(chart(), AddRow(2, RowFields("OFF", "S_ALL", event="S1")))
    c = made(c, AddRow(2, RowFields("ON", "S3", event="S1")))
    targets = [r.operand for r in c.all_steps()[1].actions[-2:]]
    assert [t.step for t in targets if isinstance(t, StepTarget)] == [None, 3]


def test_a_row_breaking_the_event_table_is_kept_and_listed_as_E020() -> None:
    out = apply_edit(chart(), AddRow(3, RowFields("N", "Q1.0", event="S0", interlocked=True)))
    assert [(d.code, d.element) for d in out.diagnostics] == [("E020", "step S3 row 2")]


@pytest.mark.parametrize(
    ("row", "why"),
    [
        (RowFields("X", "Q0.0"), "unknown qualifier 'X'"),
        (RowFields("N", "Q0.0", event="S9"), "unknown event 'S9'"),
        (RowFields("N", "Q0.0; N Q0.1"), "more than one row"),
        (RowFields("ON", "Q0.0", event="S1"), "ON needs a step"),
        (RowFields("N", ""), "the text ends too early"),
    ],
)
def test_a_row_that_does_not_read_as_one_row_is_refused(row: RowFields, why: str) -> None:
    assert why in refused(chart(), AddRow(1, row))


def test_a_row_index_outside_the_step_is_refused() -> None:
    assert "no row index 5" in refused(chart(), RemoveRow(1, 5))
    assert "no row index -1" in refused(chart(), MoveRow(1, 0, -1))


# ---------------------------------------------------------------- options and the source


def test_an_option_is_set_by_its_header_keyword() -> None:
    c = made(chart(), SetOption("skip_steps", "true"))
    assert c.options.skip_steps is True
    assert made(c, SetOption("ORDER", "CODESYS")).options.order == "codesys"


def test_an_unknown_option_or_value_is_refused_by_the_parser_table() -> None:
    assert "unknown option COLOUR" in refused(chart(), SetOption("COLOUR", "RED"))
    assert "must be TRUE or FALSE" in refused(chart(), SetOption("MESSAGES", "MAYBE"))
    assert "a name and a value" in refused(chart(), SetOption("MESSAGES", "TRUE; X := 1"))


def test_the_source_view_text_replaces_the_chart() -> None:
    text = (CHARTS / "alternative.s7g").read_text(encoding="utf-8")
    session = Session.open(chart()).apply(SetSource(text))
    assert session.refusal is None
    assert unlocated(session.chart) == unlocated(parse_chart(text, "t.s7g"))
    assert session.undo().chart == chart()


def test_a_syntax_error_in_the_source_view_is_located_in_the_source() -> None:
    text = (CHARTS / "alternative.s7g").read_text(encoding="utf-8").replace("I0.1;", "I0.1")
    out = apply_edit(chart(), make_edit("set_source", {"text": text}))
    assert out.refusal is not None
    assert [(d.code, d.loc.line) for d in out.refusal.diagnostics] == [("E001", 10)]
