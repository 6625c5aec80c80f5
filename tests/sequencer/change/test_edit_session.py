"""The table of edit operations, edits built from data, the editing session with undo and
redo, a new chart, and diagnostics mapped to the elements they concern
(``sequencer.change.edit``, ``sequencer.text.elements``)."""

from __future__ import annotations

import inspect
from pathlib import Path

import pytest

from s7graph.sequencer.change import base as edit_base
from s7graph.sequencer.change import content as edit_content
from s7graph.sequencer.change import structure as edit_structure
from s7graph.sequencer.change.base import MAX_UNDO, Edit, EditRefused
from s7graph.sequencer.change.content import AddRow, RenameStep, SetCondition, SetSource
from s7graph.sequencer.change.edit import (
    BY_NAME,
    OPERATIONS,
    Operation,
    Session,
    apply_edit,
    describe,
    make_edit,
    new_chart,
    operations_for,
)
from s7graph.sequencer.change.structure import InsertStep
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.checks.default_cpu import default_cpu_warnings
from s7graph.sequencer.checks.diagnostics import Diagnostic, warning
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.elements import (
    DeclRef,
    Ref,
    RowRef,
    SequenceRef,
    StepRef,
    TransitionRef,
    element_of,
    find,
    label,
    parse_label,
)
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from tests.paths import DOCS
from tests.sequencer.helpers import BROKEN, CHARTS

BROKEN_CHARTS = sorted(BROKEN.glob("*.s7g"))


def linear() -> Chart:
    return parse_chart((CHARTS / "linear.s7g").read_text(encoding="utf-8"), "l.s7g")


# ---------------------------------------------------------------- the table


def test_the_table_lists_every_edit_class_once_under_a_unique_name() -> None:
    classes = {
        c
        for module in (edit_content, edit_structure)
        for _, c in inspect.getmembers(module, inspect.isclass)
        if issubclass(c, Edit) and c is not Edit
    }
    assert sorted(c.__name__ for c in classes) == sorted(op.edit.__name__ for op in OPERATIONS)
    assert len(BY_NAME) == len(OPERATIONS)


def test_every_operation_names_its_element_first_and_documents_itself() -> None:
    first = {
        "step": ["step"],
        "row": ["step", "index"],
        "transition": ["transition"],
        "sequence": ["sequence"],
        "chart": [],
    }
    for op in OPERATIONS:
        names = [a.name for a in op.arguments]
        assert names[: len(first[op.target])] == first[op.target], op.name
        assert {a.type for a in op.arguments} <= {"int", "str", "bool", "int | None", "RowFields"}
        assert op.doc and op.title, op.name


def test_operations_for_a_selected_row_are_the_row_and_step_operations() -> None:
    targets = {op.target for op in operations_for(RowRef(2, 0))}
    assert targets == {"row", "step", "chart"}
    assert {op.target for op in operations_for(None)} == {"chart"}


def test_an_operation_takes_its_element_from_the_selection() -> None:
    move = BY_NAME["move_row"].on(RowRef(2, 1), to=0)
    assert make_edit("move_row", {"step": 2, "index": 1, "to": 0}) == move
    assert BY_NAME["insert_step"].on(TransitionRef(3)) == InsertStep(3)
    assert BY_NAME["add_row"].on(RowRef(2, 0), row=RowFields("N", "Q0.0")).step == 2  # type: ignore[attr-defined]
    with pytest.raises(EditRefused, match="acts on a transition; select one first"):
        BY_NAME["jump"].on(StepRef(2), to=1)


@pytest.mark.parametrize(
    ("name", "args", "why"),
    [
        ("explode", {}, "unknown edit operation 'explode'"),
        ("rename_step", {"step": 1}, "missing argument 'name'"),
        ("rename_step", {"step": 1, "name": "x", "colour": 1}, "unknown argument 'colour'"),
        ("rename_step", {"step": "1", "name": "x"}, "step must be a whole number"),
        ("rename_step", {"step": True, "name": "x"}, "step must be a whole number"),
        ("rename_step", {"step": 1, "name": ["x"]}, "name must be text"),
        ("set_initial", {"step": 1, "initial": 1}, "must be true or false"),
        ("add_row", {"step": 1, "row": "N Q0.0"}, "fields of an action row"),
        ("add_row", {"step": 1, "row": {"qualifier": "N"}}, "needs a qualifier and an operand"),
        ("add_row", {"step": 1, "row": {"qualifier": "N", "operand": 5}}, "operand must be str"),
        ("add_row", {"step": 1, "row": {"qualifier": "N", "x": ""}}, "unknown field 'x'"),
        ("jump", [1, 2], "arguments must be named"),
    ],
)
def test_an_edit_from_data_is_checked_against_the_table(name: str, args: object, why: str) -> None:
    with pytest.raises(EditRefused, match=why):
        make_edit(name, args)  # type: ignore[arg-type]


def test_an_edit_from_data_may_leave_optional_arguments_out() -> None:
    assert make_edit("insert_alternative_branch", {"step": 2}).to is None  # type: ignore[attr-defined]
    assert [a.required for a in BY_NAME["add_row"].arguments] == [True, True, False]


def test_an_undo_entry_reads_as_one_short_phrase_of_its_operation() -> None:
    """In the words of the chart, never a Python repr: ``S3``, ``T1``, a name in quotes."""
    assert describe(RenameStep(2, "Clamp part")) == 'rename S2 to "Clamp part"'
    assert describe(SetCondition(3, "I0.0 AND " * 20)) == "condition of T3"
    assert describe(InsertStep(2)) == "insert step after T2"
    assert describe(AddRow(2, RowFields("S", "Q0.0", "S1"))) == "add action row to S2"
    assert describe(make_edit("move_row", {"step": 4, "index": 0, "to": 2})) == (
        "move action row 1 of S4"  # rows counted from 1, as check prints them
    )
    assert describe(SetSource("FUNCTION_BLOCK 'x'")) == "edit in the source view"
    assert describe(RenameStep(1, "N" * 90)) == f'rename S1 to "{"N" * 21}..."'


_SAMPLE: dict[str, object] = {
    "int": 32767,
    "int | None": None,
    "str": "x" * 200,
    "bool": True,
    "RowFields": RowFields("S", "Q0.0"),
}


@pytest.mark.parametrize("op", OPERATIONS, ids=lambda op: op.name)
def test_every_operation_has_a_short_undo_phrase_of_its_own(op: Operation) -> None:
    """Every operation's ``phrase`` names only its own fields, and says an edit of it in a
    line the undo button's label holds, whatever the edit's texts."""
    edit = op.edit(**{a.name: _SAMPLE[a.type] for a in op.arguments})
    said = describe(edit)
    assert said and said[0].islower() and "{" not in said and len(said) <= 60, said
    assert [o.name for o in OPERATIONS if o.phrase == op.phrase] == [op.name]


# ---------------------------------------------------------------- a new chart


def test_a_new_chart_is_S1_with_T1_jumping_back_as_TIA_creates_it() -> None:
    c = new_chart("Seq_new", 5, 6)
    ((s1,),) = [q.steps for q in c.sequences]
    ((t1,),) = [q.transitions for q in c.sequences]
    assert (c.name, c.fb_number, c.db_number, c.file) == ("Seq_new", 5, 6, "Seq_new.s7g")
    assert (s1.number, s1.name, s1.initial) == (1, "Step1", True)
    assert (t1.number, t1.name, t1.sources, t1.targets, t1.condition) == (
        1,
        "Trans1",
        (1,),
        (1,),
        None,
    )
    assert [d.code for d in validate(c)] == ["W120"]


def test_a_new_chart_with_a_bad_name_is_refused() -> None:
    with pytest.raises(EditRefused, match="line break"):
        new_chart("two\nlines")


# ---------------------------------------------------------------- undo and redo


def test_undo_gives_back_the_very_chart_and_redo_the_edited_one() -> None:
    start = Session.open(linear())
    one = start.apply(InsertStep(1))
    two = one.apply(RenameStep(4, "Wait"))
    assert two.undo_label == 'rename S4 to "Wait"'
    assert two.undo().undo_label == "insert step after T1"
    back = two.undo().undo()
    assert back.chart is start.chart and back.diagnostics == start.diagnostics
    again = back.redo().redo()
    assert again.chart is two.chart and again.selection == two.selection
    assert not again.undone and len(again.done) == 2


def test_a_new_edit_after_undo_drops_the_redo() -> None:
    s = Session.open(linear()).apply(InsertStep(1)).undo()
    assert s.redo_label is not None
    s = s.apply(RenameStep(1, "Home"))
    assert s.redo_label is None
    assert s.redo().refusal is not None and s.redo().chart is s.chart


def test_a_refused_edit_changes_nothing_and_is_not_undoable() -> None:
    s = Session.open(linear())
    after = s.apply(RenameStep(9, "x"))
    assert after.chart is s.chart and after.done == ()
    assert after.refusal is not None and after.refusal.reason == "there is no step S9"
    assert after.apply(RenameStep(1, "y")).refusal is None


def test_undo_with_nothing_to_undo_says_so() -> None:
    s = Session.open(linear())
    assert s.undo().refusal is not None and s.undo().chart is s.chart


def test_the_history_keeps_the_last_MAX_UNDO_edits() -> None:
    s = Session.open(linear())
    for i in range(MAX_UNDO + 5):
        s = s.apply(RenameStep(1, f"n{i}"))
    assert len(s.done) == MAX_UNDO
    for _ in range(MAX_UNDO):
        s = s.undo()
    assert s.chart.all_steps()[0].name == "n4"


def test_a_session_lists_whether_the_chart_compiles() -> None:
    s = Session.open(linear())
    assert not s.has_errors
    assert s.apply(SetCondition(1, '"Unknown"')).has_errors


# ---------------------------------------------------------------- selection and diagnostics


REFS: list[Ref] = [
    StepRef(3),
    StepRef(3, "interlock"),
    StepRef(3, "supervision"),
    RowRef(2, 0),
    TransitionRef(4),
    SequenceRef(2),
    DeclRef("variable", "n"),
    DeclRef("symbol", "Start 1"),
    DeclRef("permanent", "before"),
]


@pytest.mark.parametrize("ref", REFS, ids=label)
def test_an_element_label_reads_back_as_its_reference(ref: Ref) -> None:
    assert parse_label(label(ref)) == ref


def _diagnostics(path: Path) -> tuple[Chart | None, list[Diagnostic]]:
    try:
        c = parse_chart(path.read_text(encoding="utf-8"), path.name)
    except ChartSyntaxError as exc:
        return None, exc.diagnostics
    return c, validate(c) + default_cpu_warnings(c)  # and those of s7graph check (W140)


PARSED = [p for p in BROKEN_CHARTS if _diagnostics(p)[0] is not None]  # syntax errors: no chart


@pytest.mark.parametrize("path", PARSED, ids=[p.stem for p in PARSED])
def test_every_diagnostic_of_a_broken_chart_selects_an_element_there(path: Path) -> None:
    c, diagnostics = _diagnostics(path)
    assert c is not None and diagnostics
    for d in diagnostics:
        ref = element_of(d, c)
        assert ref is not None, d
        assert find(c, ref) is not None, (d, ref)
        if d.element:
            assert label(ref) == d.element


def test_a_diagnostic_without_element_selects_the_element_at_its_place() -> None:
    c, diagnostics = _diagnostics(BROKEN / "E013_duplicate_variable.s7g")
    assert c is not None
    (d,) = diagnostics
    assert d.element == "" and element_of(d, c) == DeclRef("variable", "n")
    assert element_of(d) is None


def test_clicking_a_diagnostic_selects_its_element() -> None:
    s = Session.open(linear()).apply(SetCondition(2, '"Nowhere"'))
    (d,) = s.diagnostics
    assert s.select_diagnostic(d).selection == TransitionRef(2)


def test_selecting_an_element_that_is_not_there_is_refused() -> None:
    s = Session.open(linear())
    assert s.select(RowRef(2, 0)).selection == RowRef(2, 0)
    refused = s.select(RowRef(2, 5))
    assert refused.refusal is not None and refused.refusal.reason == (
        "there is no step S2 row 6 in the chart"
    )
    gone = s.select_diagnostic(warning("W101", "x", s.chart.loc, "step S77"))
    assert gone.refusal is not None and gone.selection is None


def test_apply_edit_refuses_what_is_not_an_edit() -> None:
    out = apply_edit(linear(), "rename everything")  # type: ignore[arg-type]
    assert out.refusal is not None and "not an edit operation: str" in out.refusal.reason


def test_the_online_change_doc_names_every_operation_and_limit() -> None:
    """docs/online-change.md, "Editing charts (core)" (once a section of the README)."""
    doc = (DOCS / "online-change.md").read_text(encoding="utf-8")
    section = doc.split("## Editing charts (core)")[1].split("\n## ")[0]
    assert [op.name for op in OPERATIONS if f"`{op.name}`" not in section] == []
    limits = [v for k, v in vars(edit_base).items() if k.startswith("MAX_")]
    assert [n for n in limits if f"{n:,}" not in section and f"{n}" not in section] == []
