"""What the editor's form offers, without a browser: the names a condition can be completed with,
how a word is completed, what Delete deletes, and which inserts a place offers."""

from __future__ import annotations

from s7graph.sequencer.text.elements import RowRef, SequenceRef, StepRef, TransitionRef
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.view.edit_forms import MAX_COMPLETIONS, completed, completions, form_for, names_for
from s7graph.web.view.editor_place import delete_of
from tests.web.bus.test_online_change import CHART


def test_the_names_of_a_chart_are_its_symbols_variables_and_step_and_transition_flags() -> None:
    chart = parse_chart(CHART, "fill.s7g")
    names = names_for(chart, ["Motor_on", "Tank full"])
    assert names[:6] == ["Motor_on", '"Tank full"', "go", "full", "empty", "pieces"]
    assert {"S1.X", "S2.T", "T3.TT"} <= set(names)
    assert len(names) == len(set(names))


def test_a_word_is_completed_by_the_names_starting_with_it_then_containing_it() -> None:
    names = ["full", "empty", "go", "S1.X", '"Tank full"', "overfull"]
    assert completions(names, "go AND fu") == ["full", '"Tank full"', "overfull"]
    assert completions(names, 'x OR "ta') == ['"Tank full"']
    assert completions(names, "S1.") == ["S1.X"]
    assert completions(names, "") == names
    assert len(completions([f"n{i}" for i in range(100)], "n")) == MAX_COMPLETIONS
    assert completed("go AND fu", "full") == "go AND full"
    assert completed('x OR "ta', '"Tank full"') == 'x OR "Tank full"'
    assert completed("go AND ", "full") == "go AND full"


def test_delete_deletes_the_element_whose_form_is_shown() -> None:
    assert delete_of(StepRef(2)).name == "delete_step"  # type: ignore[union-attr]
    assert delete_of(RowRef(2, 0)).name == "delete_step"  # type: ignore[union-attr]
    assert delete_of(TransitionRef(1)).name == "delete_transition"  # type: ignore[union-attr]
    assert delete_of(SequenceRef(1)).name == "delete_sequence"  # type: ignore[union-attr]
    assert delete_of(None) is None


def test_a_transition_offers_the_inserts_of_its_place_and_a_step_its_branch() -> None:
    chart = parse_chart(CHART, "fill.s7g")
    on_t = [op.name for op, _ in form_for(chart, TransitionRef(1)).actions]
    assert {"insert_step", "insert_simultaneous_branch", "jump", "branch_stop"} <= set(on_t)
    on_s = [op.name for op, _ in form_for(chart, StepRef(2)).actions]
    assert "insert_alternative_branch" in on_s
    assert [f.value for f in form_for(chart, TransitionRef(2)).properties][:3] == [
        "Full",
        2,
        "full",
    ]
