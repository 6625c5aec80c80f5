"""A condition exported means what it meant: read back from a TIA LAD network
(``exchange.flgnet``) or from the inline ST another IEC tool reads in a PLCopen export, it
has the same truth table. LAD's ``Not`` inverts all the power flow before it, and LAD has
no XOR; the writer draws both so that TIA computes the chart's condition."""

from __future__ import annotations

import re
from itertools import product

from hypothesis import given, settings
from hypothesis import strategies as st

from s7graph.sequencer.exchange import export_chart, import_chart
from s7graph.sequencer.text.format import format_expr
from s7graph.sequencer.text.model import Binary, Expr, Unary
from s7graph.sequencer.text.parse import parse_chart

ATOMS = ("I0.0", "I0.1", "I0.2", "M1.0", "MW2 > 5")
CHART = """FUNCTION_BLOCK "T" FB 3
SEQUENCE 1 "Main"
  INITIAL_STEP S1:
  END_STEP
  STEP S2:
    INTERLOCK := {cond};
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := {cond};
  TRANSITION T2 FROM S2 TO S1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def truth(e: Expr, env: dict[str, bool]) -> bool:
    """``e`` under ``env`` (atoms by their text: operands and comparisons)."""
    if isinstance(e, Unary) and e.op == "NOT":
        return not truth(e.operand, env)
    if isinstance(e, Binary) and e.op in ("AND", "OR", "XOR"):
        a, b = truth(e.left, env), truth(e.right, env)
        return {"AND": a and b, "OR": a or b, "XOR": a != b}[e.op]
    return env[format_expr(e)]


def table(e: Expr) -> list[bool]:
    return [truth(e, dict(zip(ATOMS, bits, strict=True))) for bits in product((0, 1), repeat=5)]


def through_lad(cond: str) -> tuple[Expr, Expr, Expr]:
    """The transition's condition as written, and the condition and interlock read back
    from the chart's SimaticML export."""
    chart = parse_chart(CHART.format(cond=cond), "t.s7g")
    back = import_chart(export_chart(chart, "simaticml").encode(), "t.xml").chart
    written = chart.sequences[0].transitions[0].condition
    seq = back.sequences[0]
    read, interlock = seq.transitions[0].condition, seq.steps[1].interlock
    assert written is not None and read is not None and interlock is not None
    return written, read, interlock


def test_a_not_after_a_contact_negates_only_its_own_operand() -> None:
    """``a AND NOT (b OR c)``: TIA's NOT would invert ``a`` too if drawn after it."""
    written, read, interlock = through_lad("I0.0 AND NOT (I0.1 OR I0.2)")
    assert table(read) == table(interlock) == table(written)


def test_xor_is_drawn_as_the_or_of_two_products() -> None:
    written, read, _ = through_lad("I0.0 XOR (I0.1 AND NOT M1.0)")
    assert table(read) == table(written)
    assert "XOR" not in format_expr(read)


CONDITIONS = st.recursive(
    st.sampled_from(ATOMS),
    lambda inner: st.one_of(
        st.builds(lambda x: f"NOT ({x})", inner),
        st.builds(
            lambda a, op, b: f"({a}) {op} ({b})",
            inner,
            st.sampled_from(("AND", "OR", "XOR")),
            inner,
        ),
    ),
    max_leaves=8,
)


def through_iec(cond: str) -> Expr | None:
    """The transition's condition read back as another IEC tool reads the PLCopen export
    (without the ``.s7g`` source s7graph keeps in ``addData``)."""
    chart = parse_chart(CHART.format(cond=cond), "t.s7g")
    xml = re.sub(r"<addData>.*?</addData>", "", export_chart(chart, "plcopen"), flags=re.S)
    return import_chart(xml.encode(), "t.xml").chart.sequences[0].transitions[0].condition


@settings(max_examples=150, deadline=None)
@given(CONDITIONS)
def test_every_condition_keeps_its_truth_table_through_lad_and_iec(cond: str) -> None:
    written, read, interlock = through_lad(cond)
    assert table(read) == table(written), cond
    assert table(interlock) == table(written), cond
    iec = through_iec(cond)
    assert iec is not None and table(iec) == table(written), cond
