"""Inserting and deleting steps, transitions, branches and sequencers as S7-GRAPH's editor
does (``sequencer.change.structure``): the chart stays consistent, or the edit is refused
naming why."""

from __future__ import annotations

from s7graph.engine.memory import Memory
from s7graph.sequencer.change.base import Edit
from s7graph.sequencer.change.edit import Session, apply_edit, make_edit, new_chart
from s7graph.sequencer.change.structure import (
    BranchStop,
    DeleteAlternativeBranch,
    DeleteSequence,
    DeleteSimultaneousBranch,
    DeleteStep,
    DeleteTransition,
    InsertAlternativeBranch,
    InsertSequence,
    InsertSimultaneousBranch,
    InsertStep,
    Jump,
)
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.cycle import GraphRuntime
from s7graph.sequencer.text.elements import SequenceRef, StepRef, TransitionRef
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import unlocated
from tests.sequencer.helpers import CHARTS


def chart(name: str) -> Chart:
    return parse_chart((CHARTS / f"{name}.s7g").read_text(encoding="utf-8"), f"{name}.s7g")


def made(c: Chart, edit: Edit) -> Chart:
    out = apply_edit(c, edit)
    assert out.refusal is None, out.refusal
    return out.chart


def refused(c: Chart, edit: Edit) -> str:
    out = apply_edit(c, edit)
    assert out.refusal is not None and out.chart is c
    return out.refusal.reason


def links(c: Chart) -> dict[int, tuple[tuple[int, ...], tuple[int, ...]]]:
    return {t.number: (t.sources, t.targets) for t in c.all_transitions()}


def codes(c: Chart) -> list[tuple[str, str]]:
    return [(d.code, d.element) for d in validate(c)]


# ---------------------------------------------------------------- inserting


def test_inserting_a_step_after_a_transition_keeps_the_chart_valid() -> None:
    out = apply_edit(chart("linear"), InsertStep(2))
    assert out.selection == StepRef(4)
    assert links(out.chart) == {1: ((1,), (2,)), 2: ((2,), (4,)), 4: ((4,), (3,)), 3: ((3,), (1,))}
    assert [(d.code, d.element) for d in out.diagnostics] == [("W120", "transition T4")]


def test_new_elements_get_the_next_number_and_S7_GRAPH_default_names() -> None:
    c = made(chart("linear"), InsertStep(1))
    s4 = next(s for s in c.all_steps() if s.number == 4)
    t4 = next(t for t in c.all_transitions() if t.number == 4)
    assert (s4.name, s4.initial, t4.name, t4.condition) == ("Step4", False, "Trans4", None)
    assert [s.number for s in c.all_steps()] == [1, 4, 2, 3]  # written after T1's step


def test_a_number_freed_by_a_deletion_is_not_reused_while_a_higher_one_is_in_use() -> None:
    c = made(chart("linear"), DeleteStep(2))
    assert max(s.number for s in made(c, InsertStep(1)).all_steps()) == 4


def test_inserting_after_a_transition_to_a_branch_stop_moves_the_stop_down() -> None:
    c = made(chart("stop"), InsertStep(2))
    assert links(c)[2] == ((2,), (4,)) and links(c)[4] == ((4,), ())


def test_deleting_the_step_just_inserted_gives_the_chart_back() -> None:
    before = chart("simultaneous")
    for t in before.all_transitions():
        inserted = made(before, InsertStep(t.number))
        new = max(s.number for s in inserted.all_steps())
        assert unlocated(made(inserted, DeleteStep(new))) == unlocated(before)


def test_an_alternative_branch_leaves_the_step_last_in_priority_and_stops() -> None:
    c = made(chart("alternative"), InsertAlternativeBranch(1))
    leaving = [t.number for t in c.all_transitions() if 1 in t.sources]
    assert leaving == [1, 2, 6]
    assert links(c)[6] == ((1,), ())
    assert codes(c) == [("W120", "transition T6")]


def test_an_alternative_branch_may_lead_to_a_step_a_jump_or_a_join() -> None:
    out = apply_edit(chart("alternative"), InsertAlternativeBranch(1, to=4))
    assert links(out.chart)[6] == ((1,), (4,)) and out.selection == TransitionRef(6)
    assert "there is no step S9" in refused(chart("alternative"), InsertAlternativeBranch(1, 9))


def test_a_simultaneous_branch_adds_a_step_below_the_transition_ending_in_a_stop() -> None:
    c = made(chart("linear"), InsertSimultaneousBranch(1))
    assert links(c)[1] == ((1,), (2, 4)) and links(c)[4] == ((4,), ())
    assert codes(c) == [("W120", "transition T4")]


def test_a_simultaneous_branch_may_join_a_later_transition() -> None:
    c = made(chart("simultaneous"), InsertSimultaneousBranch(1, join=4))
    assert links(c)[1] == ((1,), (2, 4, 6)) and links(c)[4] == ((3, 5, 6), (1,))
    assert codes(c) == []


def test_a_simultaneous_branch_that_cannot_be_opened_is_refused() -> None:
    assert "which opens it" in refused(chart("simultaneous"), InsertSimultaneousBranch(1, 1))
    assert "branch stop" in refused(chart("stop"), InsertSimultaneousBranch(2))
    assert "another sequencer" in refused(chart("two_sequencers"), InsertSimultaneousBranch(1, 10))


def test_a_branch_that_would_fork_or_join_across_sequencers_is_refused() -> None:
    """A jump may reach another sequencer; a simultaneous branch may not (E015: the chart
    would not compile). The editor refuses such a branch at the transition that jumps,
    and any edit that would make one another way, naming the steps."""
    across = made(chart("two_sequencers"), Jump(1, 10))  # T1: S1 -> S10 of sequence 2
    why = refused(across, InsertSimultaneousBranch(1))
    assert why.startswith("T1 jumps to S10 of another sequencer")
    leaving = made(chart("two_sequencers"), Jump(2, 10))  # T2: S2 -> S10 of sequence 2
    why = refused(leaving, InsertSimultaneousBranch(1, 2))  # a new path from T1 joining at T2
    assert why.startswith("a simultaneous branch joins or forks steps of different sequences")


def test_a_jump_ends_the_path_at_any_step_of_the_FB() -> None:
    c = made(chart("two_sequencers"), Jump(2, 11))
    assert links(c)[2] == ((2,), (11,))


def test_a_jump_that_leaves_a_step_without_a_way_in_is_listed_as_W101() -> None:
    assert ("W101", "step S3") in codes(made(chart("linear"), Jump(2, 1)))


def test_a_branch_stop_ends_the_path() -> None:
    assert links(made(chart("linear"), BranchStop(3)))[3] == ((3,), ())


def test_a_jump_or_stop_after_a_simultaneous_divergence_is_refused() -> None:
    assert "opens a simultaneous branch to S2, S4" in refused(chart("simultaneous"), Jump(1, 1))
    assert "opens a simultaneous branch" in refused(chart("simultaneous"), BranchStop(1))


def test_a_new_sequencer_has_an_initial_step_and_a_transition_back() -> None:
    out = apply_edit(chart("two_sequencers"), InsertSequence("Third"))
    q = out.chart.sequences[-1]
    assert out.selection == SequenceRef(3)
    assert (q.number, q.name, [s.number for s in q.steps], q.steps[0].initial) == (
        3,
        "Third",
        [12],
        True,
    )
    assert links(out.chart)[12] == ((12,), (12,))


# ---------------------------------------------------------------- deleting


def test_deleting_a_step_takes_its_following_transition() -> None:
    out = apply_edit(chart("linear"), DeleteStep(2))
    assert links(out.chart) == {1: ((1,), (3,)), 3: ((3,), (1,))}
    assert out.diagnostics == () and out.selection == TransitionRef(1)


def test_deleting_the_last_step_of_a_path_into_a_join_takes_its_preceding_transition() -> None:
    c = made(chart("simultaneous"), DeleteStep(3))
    assert links(c) == {1: ((1,), (2, 4)), 3: ((4,), (5,)), 4: ((2, 5), (1,))}
    assert codes(c) == []


def test_deleting_a_step_that_opens_an_alternative_branch_reconnects_its_paths() -> None:
    c = made(chart("alternative"), DeleteStep(4))
    assert links(c) == {1: ((1,), (2,)), 2: ((1,), (3,)), 3: ((2,), (1,)), 4: ((3,), (1,))}


def test_deleting_a_step_named_elsewhere_is_refused_naming_the_references() -> None:
    reason = refused(chart("two_sequencers"), DeleteStep(2))
    assert reason == (
        "cannot delete S2 with T2: S2 is used by step S11 row 1, transition T10; change those first"
    )


def test_deleting_the_only_step_of_a_sequencer_is_refused() -> None:
    assert "the only step of sequencer 1" in refused(new_chart(), DeleteStep(1))


def test_deleting_a_step_that_joins_and_opens_paths_is_refused() -> None:
    c = made(chart("alternative"), InsertAlternativeBranch(4, to=2))
    assert "joins or opens several paths (T3, T4, T5, T6)" in refused(c, DeleteStep(4))


def test_deleting_a_transition_that_cuts_a_path_is_refused() -> None:
    reason = refused(chart("linear"), DeleteTransition(2))
    assert reason == (
        "cannot delete T2: S2 would have no way out; S3 would have no way in (delete the step "
        "with its transition instead)"
    )


def test_deleting_an_alternative_path_without_steps_or_a_spare_jump_is_allowed() -> None:
    c = made(chart("alternative"), InsertAlternativeBranch(1, to=4))
    assert unlocated(made(c, DeleteTransition(6))) == unlocated(chart("alternative"))
    assert links(made(chart("jump"), DeleteTransition(2))) == {1: ((1,), (2,)), 3: ((2,), (1,))}


def test_deleting_a_transition_named_by_TT_is_refused() -> None:
    c = made(chart("jump"), make_edit("set_condition", {"transition": 3, "condition": "T2.TT"}))
    assert "T2 is used by transition T3" in refused(c, DeleteTransition(2))


def test_deleting_an_alternative_branch_removes_its_path_up_to_the_join() -> None:
    out = apply_edit(chart("alternative"), DeleteAlternativeBranch(2))
    assert links(out.chart) == {1: ((1,), (2,)), 3: ((2,), (4,)), 5: ((4,), (1,))}
    assert [s.number for s in out.chart.all_steps()] == [1, 2, 4]
    assert out.diagnostics == () and out.selection == StepRef(1)


def test_a_transition_that_is_no_alternative_branch_cannot_be_deleted_as_one() -> None:
    assert "does not open an alternative branch" in refused(
        chart("linear"), DeleteAlternativeBranch(2)
    )


def test_deleting_a_simultaneous_branch_leaves_the_join_waiting_for_one_path_fewer() -> None:
    out = apply_edit(chart("simultaneous"), DeleteSimultaneousBranch(4))
    assert links(out.chart) == {1: ((1,), (2,)), 2: ((2,), (3,)), 4: ((3,), (1,))}
    assert out.diagnostics == ()


def test_deleting_a_simultaneous_branch_ending_in_a_stop() -> None:
    c = made(chart("stop"), DeleteSimultaneousBranch(2))
    assert links(c) == {1: ((1,), (3,)), 3: ((3,), (1,))}


def test_a_step_that_is_no_simultaneous_branch_cannot_be_deleted_as_one() -> None:
    assert "does not start a simultaneous branch" in refused(
        chart("linear"), DeleteSimultaneousBranch(2)
    )


def test_deleting_a_sequencer_named_by_another_is_refused_and_the_only_one_too() -> None:
    two = chart("two_sequencers")
    assert "S2 is used by" in refused(two, DeleteSequence(1))
    only = made(
        made(two, make_edit("remove_row", {"step": 11, "index": 0})),
        make_edit("set_condition", {"transition": 10, "condition": "I0.6"}),
    )
    one = made(only, DeleteSequence(1))
    assert [q.number for q in one.sequences] == [2]
    assert "the only one" in refused(one, DeleteSequence(2))


# ---------------------------------------------------------------- from scratch


def test_a_chart_built_from_scratch_compiles_and_runs() -> None:
    """Three steps, an alternative branch and a jump, built as a user would in the editor."""
    s = Session.open(new_chart("Scratch", 1, 1))
    for name, args in [
        ("insert_step", {"transition": 1}),  # S1 -T1-> S2 -T2-> S1
        ("insert_step", {"transition": 2}),  # S2 -T2-> S3 -T3-> S1
        ("set_condition", {"transition": 1, "condition": "I0.0"}),
        ("set_condition", {"transition": 2, "condition": "I0.1"}),
        ("set_condition", {"transition": 3, "condition": "I0.2"}),
        ("add_row", {"step": 2, "row": {"qualifier": "N", "operand": "Q0.0"}}),
        ("add_row", {"step": 3, "row": {"qualifier": "N", "operand": "Q0.1"}}),
        ("insert_alternative_branch", {"step": 2, "to": 1}),  # T4 jumps back to S1
        ("set_condition", {"transition": 4, "condition": "I0.3"}),
    ]:
        s = s.apply(make_edit(name, args))
        assert s.refusal is None, (name, s.refusal)
    assert s.diagnostics == ()
    cc = compile_chart(s.chart)
    mem = Memory()
    rt = GraphRuntime(cc, cc.bind(mem))
    path = []
    for inputs in ({}, {"I0.0": True}, {"I0.0": False, "I0.3": True}, {"I0.3": False}):
        for address, value in inputs.items():
            mem.set(address, value)
        rt.execute({}, 0)
        path.append(sorted(cc.step_numbers[i] for i in rt.st.active))
    assert path == [[1], [2], [1], [1]]
