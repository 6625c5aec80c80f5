"""``sequencer.text.format.format_chart`` writes the model back as `.s7g` text that parses to the
same model (docs/chart-format.md): for every example, every test chart, and charts hypothesis builds
from every kind of element the parser makes."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from s7graph.engine.literals import parse_literal
from s7graph.sequencer.text.format import format_chart, format_expr
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Chart,
    ChartOptions,
    Coil,
    Const,
    Expr,
    FuncCall,
    Operand,
    Sequence,
    Step,
    StepAttr,
    StepTarget,
    SymbolDecl,
    TransAttr,
    Transition,
    Unary,
    VarDecl,
)
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import unlocated
from tests.paths import ROOT
from tests.sequencer.helpers import CHARTS

FILES = sorted(
    [*ROOT.glob("examples/*/*.s7g"), *CHARTS.glob("*.s7g")],
    key=lambda p: p.name,
)


def same_after_writing(chart: Chart) -> bool:
    text = format_chart(chart)
    return unlocated(parse_chart(text)) == unlocated(chart)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_example_reads_back_as_the_same_model(path: Path) -> None:
    chart = parse_chart(path.read_text(encoding="utf-8"), str(path))
    assert same_after_writing(chart)


def test_the_writer_adds_parentheses_only_where_precedence_needs_them() -> None:
    a, b, c = Operand("a"), Operand("b"), Operand("c")
    assert format_expr(Binary("AND", Binary("OR", a, b), c)) == "(a OR b) AND c"
    assert format_expr(Binary("OR", Binary("AND", a, b), c)) == "a AND b OR c"
    assert format_expr(Binary("-", a, Binary("-", b, c))) == "a - (b - c)"
    assert format_expr(Binary("-", Binary("-", a, b), c)) == "a - b - c"
    assert format_expr(Unary("NOT", Binary("AND", a, b))) == "NOT (a AND b)"
    assert format_expr(Binary("=", Binary("=", a, b), c)) == "(a = b) = c"


# ---------------------------------------------------------------- generated charts

_LITERALS = [
    "TRUE",
    "FALSE",
    "0",
    "5",
    "40000",
    "-7",
    "1.5",
    "T#2S",
    "T#500MS",
    "T#1H2M",
    "W#16#FF",
    "DW#16#1",
    "C#5",
    "S5T#2S",
    "'text'",
]
_VARS = ["count", "dwell", "flag", "IX1", "T5_done"]
_BITS = ["M0.1", "Q1.2"]
_ADDRESSES = ["I0.7", "Q4.1", "M10.3", "MW10", "MD12", "DB1.DBX0.0", "DB2.DBW4", "T5", "C3"]
_TEXT = st.text(st.characters(codec="utf-8", exclude_characters="\n\r\x00"), max_size=12)
_COMMENT = st.text(st.sampled_from("abc XYZ_09.-"), max_size=12).map(str.strip)


def _const(text: str) -> Const:
    if text.startswith("-"):  # the parser folds '-' into the constant
        type_name, value = parse_literal(text[1:])
        return Const(-value, type_name, text)  # type: ignore[operator]
    type_name, value = parse_literal(text)
    return Const(value, type_name, text)


operands = st.one_of(
    st.builds(Operand, st.sampled_from(_VARS)),
    st.builds(Operand, st.sampled_from(_ADDRESSES)),
    st.builds(Operand, _TEXT, st.just(True)),
)
leaves = st.one_of(
    operands,
    st.sampled_from(_LITERALS).map(_const),
    st.builds(StepAttr, st.integers(1, 300), st.sampled_from(["X", "T", "U"])),
    st.builds(TransAttr, st.integers(1, 300), st.just("TT")),
)
_OPS = [
    "OR",
    "XOR",
    "AND",
    "=",
    "<>",
    "<",
    ">",
    "<=",
    ">=",
    "SHL",
    "ROR",
    "+",
    "-",
    "*",
    "/",
    "MOD",
]


def _unary(x: Expr) -> st.SearchStrategy[Expr]:
    ops = ["NOT"] if isinstance(x, Const) else ["NOT", "-"]
    return st.sampled_from(ops).map(lambda op: Unary(op, x))  # type: ignore[arg-type]


expressions: st.SearchStrategy[Expr] = st.recursive(
    leaves,
    lambda inner: st.one_of(
        st.builds(Binary, st.sampled_from(_OPS), inner, inner),
        inner.flatmap(_unary),
        st.builds(lambda n, a: FuncCall(n, (a,)), st.sampled_from(["ABS", "SQRT", "ROUND"]), inner),
    ),
    max_leaves=6,
)


@st.composite
def rows(draw: st.DrawFn) -> ActionRow:
    kind = draw(st.sampled_from(["bit", "timed", "assign", "call", "step", "counter", "timer"]))
    event = draw(st.sampled_from([None, "S1", "S0", "V1", "V0", "L1", "L0", "A1", "R1"]))
    c = draw(st.booleans())
    if kind == "bit":
        return ActionRow(draw(st.sampled_from("NSR")), draw(operands), event, c)
    if kind == "timed":
        return ActionRow(draw(st.sampled_from("DL")), draw(operands), None, c, draw(expressions))
    if kind == "assign":
        return ActionRow("N", Assignment(draw(operands), draw(expressions)), event, c)
    if kind == "step":
        step = draw(st.one_of(st.none(), st.integers(1, 300)))
        return ActionRow(draw(st.sampled_from(["ON", "OFF"])), StepTarget(step), event, c)
    if kind == "counter":
        q = draw(st.sampled_from(["CS", "CU", "CD", "CR"]))
        return ActionRow(q, Operand("C5"), event, c, _const("C#7") if q == "CS" else None)
    if kind == "timer":
        q = draw(st.sampled_from(["TL", "TD", "TF", "TR"]))
        return ActionRow(q, Operand("T3"), event, c, _const("S5T#2S") if q != "TR" else None)
    return ActionRow("CALL", draw(calls), event, c)


calls = st.one_of(
    st.builds(
        BlockCall,
        st.sampled_from(["FB", "FC", "SFB", "SFC"]),
        st.integers(0, 99),
        st.one_of(st.none(), st.integers(1, 99), _TEXT.filter(bool)),
        st.lists(st.tuples(st.sampled_from(["IN", "PT", "EN"]), expressions), max_size=2).map(
            tuple
        ),
        st.lists(st.tuples(st.sampled_from(["Q", "ET"]), operands), max_size=1).map(tuple),
    ),
    st.builds(BlockCall, st.just(""), _TEXT, st.one_of(st.none(), _TEXT, st.integers(1, 9))),
)
permanent = st.one_of(
    st.builds(Coil, st.just("="), st.builds(Operand, st.sampled_from(_BITS)), expressions),
    st.builds(Coil, st.sampled_from(["S", "R"]), operands, expressions),
    st.builds(
        Assignment,
        st.one_of(
            st.builds(Operand, st.sampled_from(_VARS)), st.builds(Operand, _TEXT, st.just(True))
        ),
        expressions,
    ),
    calls,
)


@st.composite
def charts(draw: st.DrawFn) -> Chart:
    numbers = draw(st.lists(st.integers(1, 400), min_size=1, max_size=8, unique=True))
    cut = draw(st.integers(1, len(numbers)))
    seqs = []
    tnum = iter(draw(st.lists(st.integers(1, 400), min_size=12, max_size=12, unique=True)))
    for i, group in enumerate((numbers[:cut], numbers[cut:])):
        if not group:
            continue
        steps = tuple(
            Step(
                n,
                draw(_TEXT),
                draw(st.booleans()),
                draw(_TEXT),
                draw(st.one_of(st.none(), expressions)),
                draw(st.one_of(st.none(), expressions)),
                tuple(draw(st.lists(rows(), max_size=3))),
            )
            for n in group
        )
        trs = []
        for _ in range(draw(st.integers(0, 3))):
            src = tuple(draw(st.lists(st.sampled_from(numbers), min_size=1, max_size=2)))
            dst = tuple(draw(st.lists(st.sampled_from(numbers), max_size=2)))
            trs.append(
                Transition(
                    next(tnum), draw(_TEXT), src, dst, draw(st.one_of(st.none(), expressions))
                )
            )
        seqs.append(Sequence(i + 1, draw(_TEXT), steps, tuple(trs)))
    options = ChartOptions(
        draw(st.sampled_from(["MINIMUM", "STANDARD", "MAXIMUM", "USER"])),
        draw(st.booleans()),
        draw(st.booleans()),
        draw(st.booleans()),
        draw(st.booleans()),
        draw(st.sampled_from(["graph", "codesys"])),
    )
    types = ["INT", "BOOL", "TIME", "REAL", "STRING[10]"]
    var_decls = tuple(
        VarDecl(
            v,
            draw(st.sampled_from(types)),
            draw(st.one_of(st.none(), st.sampled_from(_LITERALS).map(_const))),
        )
        for v in draw(st.lists(st.sampled_from(_VARS), unique=True, max_size=3))
    )
    symbols = tuple(
        SymbolDecl(name, draw(st.sampled_from(_ADDRESSES)), "BOOL", draw(_COMMENT))
        for name in draw(st.lists(_TEXT, unique=True, max_size=3))
    )
    return Chart(
        draw(_TEXT),
        draw(st.one_of(st.none(), st.integers(0, 999))),
        draw(st.one_of(st.none(), st.integers(0, 999))),
        options,
        (),
        var_decls,
        symbols,
        tuple(draw(st.lists(permanent, max_size=2))),
        tuple(seqs),
        tuple(draw(st.lists(permanent, max_size=2))),
    )


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(charts())
def test_generated_charts_read_back_as_the_same_model(chart: Chart) -> None:
    assert same_after_writing(chart)


_ABOVE = st.sampled_from(["", "// a b", "(* c *)", "// d\n// e", "(* f\n   g *)"])
_TRAILING = st.sampled_from(["", "// a b", "(* c *)", "(* d *)\n// e", "(* f\n   g *)"])


@st.composite
def commented_charts(draw: st.DrawFn) -> Chart:
    """A generated chart with comments above and at the end of the line of every kind of
    element that keeps them (``sequencer.text.comments``)."""

    def note(node: Any) -> Any:
        return replace(node, comment=draw(_ABOVE), trailing=draw(_TRAILING))

    chart = draw(charts())
    sequences = tuple(
        note(
            replace(
                q,
                steps=tuple(
                    note(replace(s, actions=tuple(note(r) for r in s.actions))) for s in q.steps
                ),
                transitions=tuple(note(t) for t in q.transitions),
            )
        )
        for q in chart.sequences
    )
    vars_ = tuple(note(v) for v in chart.vars)
    return replace(note(chart), vars=vars_, sequences=sequences, end_comment=draw(_ABOVE))


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(commented_charts())
def test_generated_charts_keep_every_comment_in_its_place(chart: Chart) -> None:
    """Each comment comes back to its element, above it or at the end of its line."""
    assert same_after_writing(chart)
