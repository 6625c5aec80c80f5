"""The change summary of a download (``sequencer.change.diff``): what the edited chart changes
against the running one, keyed by step and transition number, the active steps it would
remove and the operands that may stay set."""

from __future__ import annotations

from s7graph.engine.memory import Memory
from s7graph.sequencer.change.diff import Change, StaysSet, active_steps, row_text, summarize
from s7graph.sequencer.change.edit import Session, make_edit
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.cycle import GraphRuntime
from s7graph.sequencer.text.elements import DeclRef, RowRef, StepRef, TransitionRef
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart
from tests.paths import ROOT
from tests.sequencer.helpers import CHARTS

DRILL_TEXT = (ROOT / "examples" / "drill" / "drill.s7g").read_text(encoding="utf-8")
TWO_TEXT = (CHARTS / "two_sequencers.s7g").read_text(encoding="utf-8")


def drill() -> Chart:
    return parse_chart(DRILL_TEXT, "drill.s7g")


def edited(c: Chart, *edits: tuple[str, dict[str, object]]) -> Chart:
    s = Session.open(c)
    for name, args in edits:
        s = s.apply(make_edit(name, args))
        assert s.refusal is None, s.refusal
    return s.chart


def test_the_same_chart_read_again_from_another_file_has_no_changes() -> None:
    moved = parse_chart("\n\n" + DRILL_TEXT.replace("  ", "    "), "elsewhere.s7g")
    summary = summarize(drill(), moved)
    assert summary.unchanged and summary.lines() == ()


def test_changes_are_keyed_by_step_and_transition_number() -> None:
    new = edited(
        drill(),
        ("rename_step", {"step": 4, "name": "Lower drill"}),
        ("set_condition", {"transition": 5, "condition": '"Drill_down" AND I0.0'}),
        ("set_initial", {"step": 4, "initial": True}),
        ("set_message", {"step": 4, "message": "Drill stuck"}),
        ("set_supervision", {"step": 4, "condition": "S4.U > T#9S"}),
        ("rename_transition", {"transition": 7, "name": "Raised"}),
    )
    assert summarize(drill(), new).lines() == (
        'S4: name "Lower" → "Lower drill"',
        "S4: now an initial step",
        "S4: message text changed",
        "S4: supervision added",
        "T5: condition changed",
        'T7: name "Up" → "Raised"',
    )
    changes = summarize(drill(), new).changes
    assert [c.element for c in changes] == [
        StepRef(4),
        StepRef(4),
        StepRef(4),
        StepRef(4, "supervision"),
        TransitionRef(5),
        TransitionRef(7),
    ]


def test_a_changed_value_comes_with_the_model_values_before_and_after() -> None:
    new = edited(drill(), ("set_condition", {"transition": 5, "condition": ""}))
    (change,) = summarize(drill(), new).changes
    assert change == Change(
        "removed", TransitionRef(5), "condition", "T5: condition removed", change.before, None
    )
    assert change.before is not None


def test_steps_and_transitions_added_and_removed_are_listed_with_their_paths() -> None:
    new = edited(drill(), ("delete_step", {"step": 3}), ("insert_step", {"transition": 6}))
    assert tuple(c.text for c in summarize(drill(), new).changes) == (
        'S3 "Coolant" removed',
        'S8 "Step8" added',
        "T2: TO S3 → S4",
        'T4 "Coolant flows" removed',
        "T6: TO S6 → S8",
        'T9 "Trans9" added (S8 → S6)',
    )


def test_a_renumbered_step_is_one_step_removed_and_one_added() -> None:
    new = edited(drill(), ("renumber_step", {"step": 7, "to": 70}))
    kinds = [(c.kind, c.element) for c in summarize(drill(), new).changes if c.what == "step"]
    assert kinds == [("removed", StepRef(7)), ("added", StepRef(70))]


def test_row_changes_are_listed_by_index() -> None:
    new = edited(
        drill(),
        (
            "change_row",
            {"step": 7, "index": 0, "row": {"qualifier": "R", "operand": "Q4.0", "event": "S1"}},
        ),
        ("remove_row", {"step": 7, "index": 2}),
        ("add_row", {"step": 2, "row": {"qualifier": "D", "operand": "Q4.1", "value": "T#2S"}}),
    )
    assert summarize(drill(), new).lines()[:3] == (
        "S2: row 3 added: D Q4.1, T#2S",
        'S7: row 1 changed: S1 R "Dr_mot_on" → S1 R Q4.0',
        'S7: row 3 removed: S1 R "Clamp_workp"',
    )
    elements = [c.element for c in summarize(drill(), new).changes]
    assert elements == [RowRef(2, 2), RowRef(7, 0), RowRef(7, 2)]


def test_row_text_shows_event_qualifier_mark_operand_and_value() -> None:
    c = edited(
        drill(),
        (
            "add_row",
            {
                "step": 1,
                "row": {
                    "qualifier": "CS",
                    "operand": "C 5",
                    "event": "S1",
                    "interlocked": True,
                    "value": "C#3",
                },
            },
        ),
    )
    rows = [row_text(r) for s in c.all_steps() for r in s.actions]
    assert rows[0] == "S1 CSC C5, C#3"
    assert "S1 N pieces := ..." in rows


def test_option_and_block_changes_are_listed_by_header_keyword() -> None:
    new = edited(
        drill(),
        ("set_option", {"option": "SKIP_STEPS", "value": "TRUE"}),
        ("set_option", {"option": "PARAMETERS", "value": "MAXIMUM"}),
    )
    assert summarize(drill(), new).lines() == (
        "option PARAMETERS: STANDARD → MAXIMUM",
        "option SKIP_STEPS: FALSE → TRUE",
    )
    renamed = parse_chart(DRILL_TEXT.replace('"Seq_drill" FB 1', '"Seq_drill2" FB 2'), "d.s7g")
    assert summarize(drill(), renamed).lines() == (
        "block name: Seq_drill → Seq_drill2",
        "block FB: 1 → 2",
    )


def test_the_priority_of_an_alternative_branch_is_listed_when_it_changes() -> None:
    head, t2 = DRILL_TEXT.split("  TRANSITION T2 ")
    t2, t3 = t2.split("  TRANSITION T3 ")
    t3, tail = t3.split("  TRANSITION T4 ")
    swapped = f"{head}  TRANSITION T3 {t3}  TRANSITION T2 {t2}  TRANSITION T4 {tail}"
    assert summarize(drill(), parse_chart(swapped, "d.s7g")).lines() == (
        "S2: priority of the transitions leaving it T2, T3 → T3, T2",
    )


def test_variables_symbols_and_permanent_instructions_are_compared() -> None:
    two = parse_chart(TWO_TEXT, "two.s7g")
    other = (
        TWO_TEXT.replace('"Lamp"  : Q1.0', '"Lamp"  : Q1.1')
        .replace("R M1.0 := I0.4;", "R M1.0 := I0.5;")
        .replace("\nSYMBOLS", "\nVAR k : INT; END_VAR\nSYMBOLS")
    )
    changes = summarize(two, parse_chart(other, "two.s7g")).changes
    assert [(c.kind, c.element, c.text) for c in changes] == [
        ("added", DeclRef("variable", "k"), "variable k added"),
        ("changed", DeclRef("symbol", "Lamp"), 'symbol "Lamp" changed'),
        ("changed", DeclRef("permanent", "after"), "permanent instructions after changed"),
    ]


def test_active_steps_that_the_edit_removes_are_listed_for_the_user_to_choose() -> None:
    new = edited(drill(), ("delete_step", {"step": 3}), ("delete_step", {"step": 6}))
    summary = summarize(drill(), new, active=[3, 4, 9])
    assert summary.removed_active == (3,)
    assert (
        "S3 is active and would be removed: keep the other steps, or initialize the sequencer"
        in summary.lines()
    )


def test_operands_set_by_S_rows_of_removed_steps_are_reported_with_what_resets_them() -> None:
    new = edited(drill(), ("delete_step", {"step": 3}), ("remove_row", {"step": 7, "index": 1}))
    summary = summarize(drill(), new)
    assert summary.stays_set == (StaysSet('"Cool_pump_on"', 3, ()),)
    assert summary.lines()[-1] == (
        '"Cool_pump_on", set by an S row of S3, may stay set: nothing in the edited chart resets it'
    )
    kept = edited(drill(), ("delete_step", {"step": 3}))
    assert summarize(drill(), kept).stays_set == (StaysSet('"Cool_pump_on"', 3, (RowRef(7, 1),)),)


def test_an_S_row_removed_from_a_kept_step_may_leave_its_operand_set() -> None:
    new = edited(drill(), ("remove_row", {"step": 2, "index": 1}))
    assert summarize(drill(), new).stays_set == (StaysSet('"Dr_mot_on"', 2, (RowRef(7, 0),)),)
    moved = edited(drill(), ("move_row", {"step": 2, "index": 1, "to": 0}))
    assert summarize(drill(), moved).stays_set == ()


def test_a_permanent_coil_counts_as_resetting_an_operand() -> None:
    running = parse_chart(TWO_TEXT.replace("N Q0.7;", "S1 S M1.0;"), "two.s7g")
    head, rest = TWO_TEXT.split('SEQUENCE 2 "Guard"')
    without_guard = head + rest.split("END_SEQUENCE", 1)[1].replace("S M1.0 := S11.X;", "")
    (stays,) = summarize(running, parse_chart(without_guard, "two.s7g")).stays_set
    assert stays == StaysSet("M1.0", 11, (DeclRef("permanent", "after"),))


def test_the_active_steps_of_a_running_state_are_read_by_number() -> None:
    cc = compile_chart(parse_chart(TWO_TEXT, "two.s7g"))
    rt = GraphRuntime(cc, cc.bind(Memory()))
    rt.execute({}, 0)
    assert active_steps(cc, rt.st) == (1, 10)
