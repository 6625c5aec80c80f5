"""Broken and hostile input to the editor — a 10 MB paste, a chart of 10,000 steps, an
unknown address, invalid text, nonsense from a bus — gives diagnostics or a clear refusal
naming the problem, never an exception, within the limits of ``sequencer.change.base``."""

from __future__ import annotations

import time
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from s7graph.sequencer.change.base import MAX_DEPTH, MAX_ROWS, MAX_STEPS, MAX_TEXT, EditRefused
from s7graph.sequencer.change.content import AddRow, SetCondition, SetInterlock, SetSource
from s7graph.sequencer.change.edit import OPERATIONS, Session, apply_edit, make_edit, new_chart
from s7graph.sequencer.change.structure import InsertStep
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition


def big_chart(n: int) -> Chart:
    steps = tuple(Step(i, f"Step{i}", initial=i == 1) for i in range(1, n + 1))
    trans = tuple(Transition(i, "", (i,), (i % n + 1,)) for i in range(1, n + 1))
    return replace(new_chart("Big"), sequences=(Sequence(1, "", steps, trans),))


def big_text(n: int) -> str:
    body = "".join(
        f"STEP S{i}: END_STEP TRANSITION T{i} FROM S{i} TO S{i % n + 1};\n" for i in range(1, n + 1)
    )
    return f'FUNCTION_BLOCK "Big"\nSEQUENCE 1\n{body}END_SEQUENCE\nEND_FUNCTION_BLOCK\n'


def test_a_10_MB_condition_is_refused_at_once_naming_its_size() -> None:
    start = time.perf_counter()
    out = apply_edit(new_chart(), SetCondition(1, "I0.0 AND " * 1_200_000))
    assert out.refusal is not None
    assert out.refusal.reason == (
        f"condition of T1 has 10,800,000 characters; at most {MAX_TEXT:,} are accepted"
    )
    assert time.perf_counter() - start < 1.0


def test_a_10_MB_source_text_is_refused_naming_its_size() -> None:
    out = apply_edit(new_chart(), SetSource("x" * 10_000_000))
    assert out.refusal is not None and "the source has 10,000,000 characters" in out.refusal.reason


def test_a_chart_of_10000_steps_is_refused_by_the_editor() -> None:
    with pytest.raises(EditRefused, match="the chart has 10,000 steps; the editor takes at most"):
        Session.open(big_chart(10_000))
    out = apply_edit(new_chart(), SetSource(big_text(10_000)))
    assert out.refusal is not None and "10,000 steps" in out.refusal.reason


def test_growing_a_chart_beyond_the_limit_is_refused() -> None:
    s = Session.open(big_chart(MAX_STEPS))
    assert s.apply(InsertStep(1)).refusal is not None
    assert "1,001 steps" in s.apply(InsertStep(1)).refusal.reason  # type: ignore[union-attr]


def test_a_step_holds_at_most_MAX_ROWS_rows() -> None:
    c = new_chart()
    for _ in range(MAX_ROWS):
        c = apply_edit(c, AddRow(1, RowFields("N", "Q0.0"))).chart
    assert len(c.all_steps()[0].actions) == MAX_ROWS
    out = apply_edit(c, AddRow(1, RowFields("N", "Q0.1")))
    assert out.refusal is not None and f"{MAX_ROWS} rows" in out.refusal.reason


def test_a_condition_nested_too_deeply_is_refused() -> None:
    """A chain of contacts is not nesting (the parser builds it balanced); operators nested
    in each other beyond the parser's limit are refused, naming the place."""
    long_chain = " AND ".join(["I0.0"] * (MAX_DEPTH + 10))
    assert apply_edit(new_chart(), SetInterlock(1, long_chain)).made
    nested = "".join(f"(I0.{k % 8} {'AND' if k % 2 else 'OR'} " for k in range(60))
    out = apply_edit(new_chart(), SetInterlock(1, nested + "I0.0" + ")" * 60))
    assert out.refusal is not None and "nested deeper than 32 levels" in out.refusal.reason
    assert "line 1, column" in out.refusal.reason
    nested_parentheses = "(" * 2000 + "I0.0" + ")" * 2000
    assert apply_edit(new_chart(), SetInterlock(1, nested_parentheses)).made


def test_an_unknown_address_is_kept_and_listed_as_E041() -> None:
    out = apply_edit(new_chart(), SetCondition(1, "I0.9 OR QW99999 > 3"))
    assert out.made
    found = [(d.code, d.element, d.loc.col) for d in out.diagnostics]
    assert ("E041", "transition T1", 1) in found and ("E041", "transition T1", 9) in found


TEXT_OPS = [(op.name, a.name) for op in OPERATIONS for a in op.arguments if a.type == "str"]
NUMBERS = st.one_of(st.integers(-5, 5), st.integers(), st.just(2**80))
VALUES = st.one_of(
    st.text(max_size=200), st.none(), st.booleans(), NUMBERS, st.lists(st.integers())
)


@settings(max_examples=150, deadline=None)
@given(
    op=st.sampled_from(OPERATIONS),
    values=st.dictionaries(
        st.sampled_from(
            [
                "step",
                "transition",
                "sequence",
                "index",
                "to",
                "join",
                "name",
                "text",
                "condition",
                "row",
                "at",
                "option",
                "value",
                "message",
                "initial",
                "x",
            ]
        ),
        VALUES,
        max_size=4,
    ),
)
def test_any_data_from_a_bus_gives_an_edit_or_a_refusal(
    op: object, values: dict[str, object]
) -> None:
    try:
        edit = make_edit(op.name, values)  # type: ignore[attr-defined]
    except EditRefused as exc:
        assert exc.reason
        return
    out = apply_edit(new_chart(), edit)
    assert out.made or (out.refusal is not None and out.refusal.reason)


@settings(max_examples=200, deadline=None)
@given(which=st.sampled_from(TEXT_OPS), text=st.text(max_size=300))
def test_any_text_typed_into_any_field_gives_diagnostics_or_a_refusal(
    which: tuple[str, str], text: str
) -> None:
    name, field = which
    op = next(o for o in OPERATIONS if o.name == name)
    args: dict[str, object] = {a.name: 1 if a.type == "int" else "x" for a in op.arguments}
    args[field] = text
    out = apply_edit(new_chart(), make_edit(name, args))
    assert out.made or (out.refusal is not None and out.refusal.reason)


@settings(max_examples=200, deadline=None)
@given(
    qualifier=st.sampled_from(["N", "S", "R", "D", "L", "CALL", "ON", "OFF", "CS", "CU", "TL"]),
    event=st.sampled_from(["", "S1", "S0", "V1", "L0"]),
    interlocked=st.booleans(),
    operand=st.text(max_size=60),
    value=st.text(max_size=20),
)
def test_any_row_fields_give_a_row_or_a_refusal(
    qualifier: str, event: str, interlocked: bool, operand: str, value: str
) -> None:
    row = RowFields(qualifier, operand, event, interlocked, value)
    out = apply_edit(new_chart(), AddRow(1, row))
    assert out.made or (out.refusal is not None and out.refusal.reason)
