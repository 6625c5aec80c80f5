"""The validator reports all problems at once, with types and the limits of docs/semantics.md,
"Structure"."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import CHARTS


def codes(text: str) -> list[str]:
    return [d.code for d in validate(parse_chart(text, "v.s7g"))]


def one_step(rows: str = "N Q0.0;", cond: str = "I0.0", header: str = "") -> str:
    return (
        f'FUNCTION_BLOCK "V"\n{header}\nSEQUENCE 1\n  INITIAL_STEP S1:\n    {rows}\n  END_STEP\n'
        f"  TRANSITION T1 FROM S1 TO S1 := {cond};\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )


@pytest.mark.parametrize(
    "path", [p for p in sorted(CHARTS.glob("*.s7g")) if p.stem != "spec_example"], ids=str
)
def test_sample_charts_are_clean(path: Path) -> None:
    assert validate(parse_chart(path.read_text(encoding="utf-8"), path.name)) == []


def test_all_problems_are_reported_at_once() -> None:
    text = one_step(rows="S0 NC Q0.0; L Q0.1; S1 ON S9;", cond='"Nowhere" AND T7.TT')
    assert sorted(codes(text)) == ["E020", "E021", "E026", "E040", "E044", "W122"]


def test_integer_literal_fits_dint_and_word_address_compares_as_int() -> None:
    header = "VAR d : DINT := 5; END_VAR"
    assert (
        codes(one_step(rows="S1 N d := d + 1;", cond="MW10 > 3 AND d >= 70000", header=header))
        == []
    )


def test_time_literal_compared_with_int_variable_is_an_error() -> None:
    assert codes(one_step(cond="n > T#1S", header="VAR n : INT; END_VAR")) == ["E030"]


def test_words_compare_only_as_int_dint_real_time() -> None:
    assert codes(one_step(cond="w = w", header="VAR w : WORD; END_VAR")) == ["E030"]


def test_bitwise_word_operators_and_functions_per_book_table() -> None:
    header = "VAR w : WORD; d : DWORD; i : INT; r : REAL; END_VAR"
    rows = "S1 N w := w AND 16#FF; S1 N d := d ROL 3; S1 N i := BCD_TO_NUM(w); S1 N r := SIN(r);"
    assert codes(one_step(rows=rows, header=header)) == []
    assert codes(one_step(rows="S1 N w := w ROL 3;", header=header)) == ["E032"]
    assert codes(one_step(rows="S1 N i := SQRT(i);", header=header)) == ["E033"]


def test_coil_in_permanent_needs_a_bit_target() -> None:
    header = "VAR n : INT; END_VAR\nPERMANENT BEFORE\n  S n := I0.0;\nEND_PERMANENT"
    assert codes(one_step(header=header)) == ["E031"]


def test_condition_may_not_hold_arithmetic_or_functions() -> None:
    header = "VAR r : REAL; END_VAR"
    assert codes(one_step(cond="ABS(r) > 1.0", header=header)) == ["E034"]


def test_more_than_32_condition_elements_warn() -> None:
    cond = " AND ".join(f"I{i // 8}.{i % 8}" for i in range(33))
    assert codes(one_step(cond=cond)) == ["W110"]
    cond32 = " AND ".join(f"I{i // 8}.{i % 8}" for i in range(32))
    assert codes(one_step(cond=cond32)) == []


def test_more_than_eight_sequencers_warn() -> None:
    seqs = "".join(
        f"SEQUENCE {k}\n  INITIAL_STEP S{k}: N Q0.0; END_STEP\n"
        f"  TRANSITION T{k} FROM S{k} TO S{k} := I0.0;\nEND_SEQUENCE\n"
        for k in range(1, 10)
    )
    assert codes(f'FUNCTION_BLOCK "V"\n{seqs}END_FUNCTION_BLOCK\n') == ["W110"]


def test_join_of_a_proper_simultaneous_branch_does_not_warn() -> None:
    text = (CHARTS / "simultaneous.s7g").read_text(encoding="utf-8")
    assert "W130" not in codes(text)


def test_alternative_transitions_with_identical_conditions_are_fine() -> None:
    text = (
        'FUNCTION_BLOCK "V"\nSEQUENCE 1\n  INITIAL_STEP S1: N Q0.0; END_STEP\n'
        "  STEP S2: N Q0.1; END_STEP\n  STEP S3: N Q0.2; END_STEP\n"
        "  TRANSITION T1 FROM S1 TO S2 := I0.0;\n  TRANSITION T2 FROM S1 TO S3 := I0.0;\n"
        "  TRANSITION T3 FROM S2 TO S1 := I0.1;\n  TRANSITION T4 FROM S3 TO S1 := I0.1;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    assert codes(text) == []


def test_fb_pins_are_readable_operands() -> None:
    assert codes(one_step(cond="ERR_FLT OR NOT AUTO_ON")) == []


@pytest.mark.parametrize(
    ("numbers", "expected"),
    [
        ("FB 1 DB 65535", []),
        ("FB 0 DB 1", ["E004"]),
        ("FB 1 DB 0", ["E004"]),
        ("FB 70000 DB 70000", ["E004", "E004"]),
    ],
)
def test_the_header_fb_and_db_numbers_are_block_numbers(numbers: str, expected: list[str]) -> None:
    text = one_step().replace('FUNCTION_BLOCK "V"', f'FUNCTION_BLOCK "V" {numbers}')
    assert codes(text) == expected


def test_w140_of_an_scl_source_names_its_block_as_the_scl_compilers_messages_do() -> None:
    """An S7-SCL source's W140 names the block ``OB1``, ``FC10`` — as E211 names ``FB1`` —
    not ``OB 1``."""
    from s7graph.sequencer.checks.default_cpu import scl_default_cpu_warnings
    from s7graph.steps.scl.parse import parse_source

    source = parse_source(
        "ORGANIZATION_BLOCK OB1\nBEGIN\n  %MW300 := 5;\nEND_ORGANIZATION_BLOCK\n"
        "FUNCTION FC10 : VOID\nBEGIN\n  %Q200.0 := TRUE;\nEND_FUNCTION\n",
        "t.scl",
    )
    assert [(d.loc.line, d.element) for d in scl_default_cpu_warnings(source)] == [
        (3, "OB1"),
        (7, "FC10"),
    ]
