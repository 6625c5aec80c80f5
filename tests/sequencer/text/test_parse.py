"""The `.s7g` parser builds the chart model of docs/chart-format.md with a place on every
element."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.text.enclosing import enclosing_element
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Coil,
    Const,
    Operand,
    StepAttr,
    StepTarget,
    TransAttr,
)
from s7graph.sequencer.text.parse import MAX_CHART_BYTES, ChartSyntaxError, chart_text, parse_chart
from s7graph.sequencer.text.walk import unlocated
from s7graph.steps.syntax import chain
from tests.sequencer.helpers import CHARTS


def chart_with_rows(rows: str, *, header: str = "") -> list[ActionRow]:
    text = (
        f'FUNCTION_BLOCK "T"\n{header}\nSEQUENCE 1\n  INITIAL_STEP S1:\n{rows}\n  END_STEP\n'
        "  STEP S2: END_STEP\n  TRANSITION T1 FROM S1 TO S2 := I0.0;\nEND_SEQUENCE\n"
        "END_FUNCTION_BLOCK\n"
    )
    return list(parse_chart(text, "t.s7g").sequences[0].steps[0].actions)


def test_spec_section_3_example_parses_verbatim() -> None:
    chart = parse_chart((CHARTS / "spec_example.s7g").read_text(encoding="utf-8"), "spec.s7g")
    assert chart.name == "Seq_drill"
    assert chart.options.messages is True and chart.options.parameters == "STANDARD"
    assert [v.name for v in chart.vars] == ["count", "dwell"]
    assert chart.vars[1].init == Const(500, "TIME", "T#500MS", chart.vars[1].init.loc)  # type: ignore[union-attr]
    assert [s.address for s in chart.symbols] == ["I0.7", "Q0.0"]
    assert isinstance(chart.before[0], Coil) and isinstance(chart.before[1], BlockCall)
    s2 = chart.sequences[0].steps[1]
    assert (s2.number, s2.name, s2.message) == (2, "Clamp", "Work piece not clamped")
    assert [(r.event, r.qualifier) for r in s2.actions] == [
        (None, "N"),
        ("S1", "N"),
        ("V1", "S"),
        (None, "D"),
    ]
    t = {t.number: t for t in chart.sequences[0].transitions}
    assert t[2].targets == (3, 6) and t[3].sources == (5, 7) and t[5].targets == ()
    assert (t[1].loc.line, t[1].loc.col) == (23, 3)
    assert (t[3].source_locs[1].line, t[3].source_locs[1].col) == (25, 27)


@pytest.mark.parametrize("path", sorted(CHARTS.glob("*.s7g")), ids=lambda p: p.stem)
def test_every_sample_chart_parses(path: Path) -> None:
    assert parse_chart(path.read_text(encoding="utf-8"), path.name).sequences


def test_interlock_mark_joined_or_apart_means_the_same() -> None:
    rows = chart_with_rows("    NC Q0.0; N C Q0.1; S1 RC Q1.0; S1 SC Q1.1; CALLC FC 2;")
    assert [(r.qualifier, r.interlocked) for r in rows] == [
        ("N", True),
        ("N", True),
        ("R", True),
        ("S", True),
        ("CALL", True),
    ]


def test_a_variable_named_c_is_assigned_not_taken_for_the_interlock_mark() -> None:
    """``N C := …`` assigns the variable C; ``N C x := …`` is the mark, then an assignment."""
    rows = chart_with_rows(
        "    S0 N C := MW0 AND W#16#FFF0; N c := 1; N C E := C;",
        header="VAR C : WORD; E : WORD; END_VAR",
    )
    assert [(r.qualifier, r.interlocked) for r in rows] == [("N", False)] * 2 + [("N", True)]
    assert [r.operand.target.name for r in rows] == ["C", "c", "E"]  # type: ignore[union-attr]


def test_counter_qualifiers_are_not_s_or_r_with_the_mark() -> None:
    rows = chart_with_rows("    S1 CS C 5, C#5; S1 CU C 5; S1 CU C C 6; S1 CR C2; S1 CD C3;")
    assert [(r.qualifier, r.interlocked) for r in rows] == [
        ("CS", False),
        ("CU", False),
        ("CU", True),
        ("CR", False),
        ("CD", False),
    ]
    assert [r.operand.name for r in rows] == ["C5", "C5", "C6", "C2", "C3"]  # type: ignore[union-attr]
    assert rows[0].value == Const(5, "WORD", "C#5", rows[0].value.loc)  # type: ignore[union-attr]


def test_several_rows_share_a_line_and_keep_their_columns() -> None:
    rows = chart_with_rows("    N Q0.0; D Q0.3, T#2S;   L M1.0, T#1S;")
    assert [(r.loc.line, r.loc.col) for r in rows] == [(5, 5), (5, 13), (5, 29)]
    assert rows[1].value.value == 2000  # type: ignore[union-attr]


def test_addresses_may_hold_blanks_and_are_stored_without() -> None:
    rows = chart_with_rows("    N Q 0.0; S1 TL T 5, S5T#2S;")
    assert rows[0].operand == Operand("Q0.0", False, rows[0].operand.loc)  # type: ignore[union-attr]
    assert rows[1].operand.name == "T5"  # type: ignore[union-attr]


def test_on_off_and_s_all_become_step_targets() -> None:
    rows = chart_with_rows("    S1 ON S2; L1 OFF S_ALL;")
    assert rows[0].operand == StepTarget(2, rows[0].operand.loc)
    assert rows[1].operand == StepTarget(None, rows[1].operand.loc)


def test_n_with_assignment_is_an_assignment_row() -> None:
    (row,) = chart_with_rows(
        "    S1 N n := ABS(r) * -2.5;", header="VAR n : REAL; r : REAL; END_VAR"
    )
    assert isinstance(row.operand, Assignment)
    expr = row.operand.expr
    assert isinstance(expr, Binary) and expr.op == "*"
    assert isinstance(expr.right, Const) and expr.right.value == -2.5


def test_call_forms_give_kind_block_instance_and_parameters() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nPERMANENT BEFORE\n  CALL FB 5, DB 6 (IN1 := I0.0, OUT1 => Q0.1);\n'
        '  CALL "Mixer", "MixerDB";\n  CALL SFC 46;\nEND_PERMANENT\nEND_FUNCTION_BLOCK\n'
    )
    calls = parse_chart(text).before
    assert [(c.kind, c.block, c.instance) for c in calls] == [  # type: ignore[union-attr]
        ("FB", 5, 6),
        ("", "Mixer", "MixerDB"),
        ("SFC", 46, None),
    ]
    assert calls[0].inputs[0][0] == "IN1" and calls[0].outputs[0][1].name == "Q0.1"  # type: ignore[union-attr]


def test_permanent_bit_write_is_a_coil_and_s_r_are_latching_coils() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nPERMANENT AFTER\n  M0.1 := I0.0 AND NOT I0.1;\n  S M0.2 := I0.3;\n'
        "  R M0.2 := I0.4;\nEND_PERMANENT\nEND_FUNCTION_BLOCK\n"
    )
    after = parse_chart(text).after
    assert [c.kind for c in after] == ["=", "S", "R"]  # type: ignore[union-attr]


def test_keywords_are_case_insensitive_and_comments_are_ignored() -> None:
    text = (
        'function_block "t" (* a\nblock comment *)\nsequence 1 // line comment\n'
        "  initial_step s1: n q0.0; end_step\n  transition t1 from s1 to s1 := i0.0;\n"
        "end_sequence\nend_function_block\n"
    )
    chart = parse_chart(text)
    assert chart.all_steps()[0].initial and chart.all_transitions()[0].sources == (1,)


def test_symbol_comment_is_the_trailing_line_comment() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nSYMBOLS\n  "Start" : I0.0 : BOOL;  // start button\n'
        '  "Stop" : I0.1 : BOOL;\nEND_SYMBOLS\nEND_FUNCTION_BLOCK\n'
    )
    assert [s.comment for s in parse_chart(text).symbols] == ["start button", ""]


def test_header_numbers_and_extra_options() -> None:
    text = (
        'FUNCTION_BLOCK "T" FB 7 DB 8\n  ORDER := CODESYS; ACK_FORCES_SWITCH := TRUE;\n'
        "END_FUNCTION_BLOCK\n"
    )
    chart = parse_chart(text)
    assert (chart.fb_number, chart.db_number) == (7, 8)
    assert chart.options.order == "codesys" and chart.options.ack_forces_switch is True


def test_empty_or_omitted_transition_condition_is_none() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: END_STEP\n'
        "  TRANSITION T1 FROM S1 TO S1 := ;\n  TRANSITION T2 FROM S1 TO STOP;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    assert [t.condition for t in parse_chart(text).all_transitions()] == [None, None]


def test_step_and_transition_attributes_in_conditions() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: END_STEP\n'
        "  TRANSITION T1 FROM S1 TO S1 := S1.X AND T1.TT AND S1.T > T#2S;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    cond = parse_chart(text).all_transitions()[0].condition
    assert isinstance(cond, Binary) and isinstance(cond.left, Binary)
    assert isinstance(cond.left.left, StepAttr) and isinstance(cond.left.right, TransAttr)


def test_syntax_error_names_place_and_what_was_expected() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: END_STEP\n'
        "  TRANSITION T1 FROM S1 TO X2;\n"
    )
    with pytest.raises(ChartSyntaxError) as info:
        parse_chart(text, "x.s7g")
    (d, *_) = info.value.diagnostics
    assert (d.code, d.loc.file, d.loc.line, d.loc.col) == ("E001", "x.s7g", 4, 28)
    assert "'X2'" in d.message and "a step like S3" in d.message


def test_parser_recovers_and_reports_every_syntax_error() -> None:
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1:\n    X Q0.0;\n    N Q0.1;\n  END_STEP\n'
        "  TRANSITION T1 FROM S1 TO S1 := I0.0 AND ;\n  TRANSITION T2 FROM S1 TO S1 := I0.1;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    with pytest.raises(ChartSyntaxError) as info:
        parse_chart(text)
    assert [(d.loc.line, d.loc.col) for d in info.value.diagnostics] == [(4, 5), (7, 43)]


def test_a_line_comment_may_follow_an_operand_before_the_semicolon() -> None:
    """``//`` starts a comment even where ``/`` could divide (the comment outranks MULOP)."""
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: END_STEP\n'
        "  TRANSITION T1 FROM S1 TO S1 := I0.0 // the start button\n  ;\n"
        "  TRANSITION T2 FROM S1 TO S1 := MW10 / 2 > 3;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    t1, t2 = parse_chart(text).all_transitions()
    assert isinstance(t1.condition, Operand) and t1.condition.name == "I0.0"
    assert isinstance(t2.condition, Binary) and t2.condition.op == ">"


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 7, 8, 9, 31, 64, 70])
def test_a_written_chain_parses_to_the_shape_steps_syntax_chain_builds(n: int) -> None:
    """Importers build chains with ``steps.syntax.chain``; it is the parser's shape."""
    contacts = [f"I{k // 8}.{k % 8}" for k in range(n)]
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: END_STEP\n  STEP S2: END_STEP\n'
        f"  TRANSITION T1 FROM S1 TO S2 := {' AND '.join(contacts)};\nEND_SEQUENCE\n"
        "END_FUNCTION_BLOCK\n"
    )
    condition = parse_chart(text, "t.s7g").all_transitions()[0].condition
    expected = chain("AND", [Operand(c) for c in contacts])
    assert unlocated(condition) == unlocated(expected)


def test_a_chart_file_over_the_size_limit_is_refused_before_it_is_parsed() -> None:
    """Parsing tens of megabytes holds a shell for minutes: a file over the limit is one
    located E001 saying both sizes, and one at the limit is read."""
    assert chart_text(b" " * MAX_CHART_BYTES, "big.s7g") == " " * MAX_CHART_BYTES
    with pytest.raises(ChartSyntaxError) as refused:
        chart_text(b" " * (MAX_CHART_BYTES + 1), "big.s7g")
    (d,) = refused.value.diagnostics
    assert (d.code, d.loc.file, d.loc.line) == ("E001", "big.s7g", 1)
    assert d.message == "the file has 10,000,001 bytes: a chart file has at most 10,000,000"


def test_the_element_of_a_place_is_read_past_comments_and_quoted_texts() -> None:
    text = (
        'SEQUENCE 1\n  STEP S2 "a;b": (* END_STEP *) N Q0.0;\n'
        "  // TRANSITION T9\n  END_STEP\n  TRANSITION T1 FROM S1 TO S2 := I0.0;\n"
        "PERMANENT BEFORE\n  M0.0 := I0.0;\nEND_PERMANENT\n"
    )
    assert enclosing_element(text, 2, 40) == "step S2"
    assert enclosing_element(text, 3, 10) == "step S2"
    assert enclosing_element(text, 5, 30) == "transition T1"
    assert enclosing_element(text, 5, 40) == ""
    assert enclosing_element(text, 7, 5) == "permanent before"
    assert enclosing_element(text, 8, 14) == ""


def test_a_comment_never_closed_is_one_error_where_it_opens() -> None:
    """A file cut inside a ``(*`` comment (truncated, or ``*)`` forgotten) was an error for
    every word of the comment, the first ``unexpected '('`` at its start; now one E002
    there, with the errors before it kept, and ``(*`` in a string or a closed comment is
    no opening."""
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: N "a(*b"; END_STEP (* ok *)\n'
        "  STEP S2: END_STEP\n  (* the rest: not done\n  TRANSITION T1 FROM S1 TO S2 := I0.0;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    with pytest.raises(ChartSyntaxError) as caught:
        parse_chart(text, "t.s7g")
    (only,) = caught.value.diagnostics
    assert (only.code, only.loc.line, only.loc.col) == ("E002", 5, 3)
    assert only.message == "the comment opened at line 5 is never closed (missing '*)')"
    broken = text.replace("STEP S2: END_STEP", "STEP S2 := END_STEP")
    with pytest.raises(ChartSyntaxError) as caught:
        parse_chart(broken, "t.s7g")
    assert [d.code for d in caught.value.diagnostics] == ["E001", "E002"]


def test_a_call_given_a_qualifier_says_call_is_the_qualifier() -> None:
    with pytest.raises(ChartSyntaxError) as info:
        chart_with_rows("    N CALL FB 17, DB 10 (go := TRUE);")
    (d,) = info.value.diagnostics
    assert (d.code, d.loc.line, d.loc.col) == ("E001", 5, 7)
    assert d.message == (
        "a block call is an action of its own: write CALL FB 17, … with no qualifier before"
        " CALL (CALL is the qualifier, as in S7-GRAPH)"
    )


@pytest.mark.parametrize("digits", ["١٢", "１２"])
def test_a_number_of_non_ascii_digits_is_a_syntax_error_where_it_stands(digits: str) -> None:
    """S7 numbers are written with the digits 0-9 only: Arabic-Indic or full-width digits
    are not read as 12."""
    text = (
        'FUNCTION_BLOCK "T"\nSEQUENCE 1\n  INITIAL_STEP S1: END_STEP\n  STEP S2: END_STEP\n'
        f"  TRANSITION T1 FROM S1 TO S2 := MW0 < {digits};\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    with pytest.raises(ChartSyntaxError) as info:
        parse_chart(text, "x.s7g")
    (d, *_) = info.value.diagnostics
    assert (d.code, d.loc.line, d.loc.col) == ("E001", 5, 40)
    assert d.message.startswith(f"unexpected character {digits[0]!r} (S7 numbers have the digits")
