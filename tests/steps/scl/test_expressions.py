"""Expressions: S7-SCL precedence, INT/DINT wraparound and the OK flag, REAL, conversions,
bit, numeric and string functions, typed literals (docs/scl.md, "Expressions" and
"Functions")."""

from __future__ import annotations

import math

import pytest

from s7graph import sfb
from s7graph.steps.scl import check_scl
from tests.steps.scl.helpers import codes, errors, value


@pytest.mark.parametrize(
    ("expr", "rtype", "expected"),
    [
        ("2 + 3 * 4", "INT", 14),
        ("(2 + 3) * 4", "INT", 20),
        ("-2 ** 2", "REAL", -4.0),  # ** binds tighter than unary minus
        ("2 ** 3 ** 2", "REAL", 64.0),  # left to right
        ("10 - 4 - 3", "INT", 3),
        ("17 MOD 5 * 2", "INT", 4),  # MOD and * on one level, left to right
        ("7 DIV 2 + 1", "INT", 4),
        ("NOT FALSE AND FALSE", "BOOL", False),  # NOT before AND
        ("TRUE OR FALSE AND FALSE", "BOOL", True),  # AND before OR
        ("TRUE XOR TRUE OR TRUE", "BOOL", True),  # XOR before OR
        ("FALSE AND TRUE XOR TRUE", "BOOL", True),  # AND before XOR
        ("1 < 2 = 3 < 4", "BOOL", True),  # < before =
        ("2 + 3 > 4 AND 1 = 1", "BOOL", True),
        ("TRUE & NOT FALSE", "BOOL", True),
        ("3 <> 4", "BOOL", True),
        ("4 >= 4", "BOOL", True),
    ],
)
def test_precedence_table(expr: str, rtype: str, expected: object) -> None:
    assert value(expr, rtype) == (expected, True)


@pytest.mark.parametrize(
    ("expr", "rtype", "expected", "ok"),
    [
        ("a + 1", "INT", -32768, False),  # a = 32767
        ("a * 2", "INT", -2, False),
        ("-b", "INT", -32768, False),  # b = -32768
        ("b - 1", "INT", 32767, False),
        ("a + 0", "INT", 32767, True),
        ("d + 1", "DINT", -(2**31), False),  # d = 2147483647
        ("d * d", "DINT", 1, False),
        ("a / 0", "INT", 0, False),
        ("a MOD 0", "INT", 0, False),
        ("b / -1", "INT", -32768, False),
        ("-7 / 2", "INT", -3, True),  # toward zero
        ("-7 MOD 2", "INT", -1, True),  # the dividend's sign
        ("7 MOD -2", "INT", 1, True),
        ("b / 2", "INT", -16384, True),  # by a constant: inline, the same rules
        ("(b + 1) DIV 10", "INT", -3276, True),
        ("b MOD 10", "INT", -8, True),
        ("a MOD 10 + a / 10", "INT", 3283, True),
        ("d DIV 16", "DINT", 134217727, True),
        ("-d MOD 16", "DINT", -15, True),
        ("d - d + a", "DINT", 32767, True),  # INT widened to DINT first
        ("a + INT_TO_DINT(1)", "DINT", 32768, True),
        ("a + d", "DINT", -(2**31) + 32766, False),
        ("DINT_TO_INT(d)", "INT", -1, False),
        ("DINT_TO_INT(INT_TO_DINT(a))", "INT", 32767, True),
        ("ABS(b)", "INT", -32768, False),
        ("T#24D20H31M23S647MS + T#1MS", "TIME", -(2**31), False),
    ],
)
def test_integer_overflow_wraps_and_clears_ok(
    expr: str, rtype: str, expected: int, ok: bool
) -> None:
    decls = "a : INT := 32767; b : INT := -32768; d : DINT := 2147483647;"
    assert value(expr, rtype, decls) == (expected, ok)


def test_real_is_rounded_to_32_bits_and_overflows_to_infinity() -> None:
    got, ok = value("0.1 + 0.2", "REAL")
    assert ok and got == pytest.approx(0.3, abs=1e-7) and got != 0.1 + 0.2
    assert value("1.0E38 * 10.0", "REAL") == (math.inf, False)
    # over the largest REAL by less than half its last step: rounded back to it, no overflow
    assert value("3.4028234E38 + 1.0E31", "REAL") == (3.4028234663852886e38, True)
    assert value("3.4028234E38 + 2.0E31", "REAL") == (math.inf, False)
    assert value("1.0 / 0.0", "REAL") == (math.inf, False)
    got, ok = value("SQRT(-1.0)", "REAL")
    assert math.isnan(got) and not ok
    assert value("16777217", "REAL") == (16777216.0, True)
    assert value("DINT_TO_REAL(16777217)", "REAL") == (16777216.0, True)


@pytest.mark.parametrize(
    ("expr", "expected"),
    [
        ("EXP(1000.0)", math.inf),
        ("EXPD(400.0)", math.inf),
        ("LN(0.0)", -math.inf),
        ("LOG(0.0)", -math.inf),
        ("(-10.0) ** 1001.0", -math.inf),
        ("10.0 ** 1001.0", math.inf),
    ],
)
def test_a_real_function_beyond_the_range_gives_the_infinity_the_fpu_gives(
    expr: str, expected: float
) -> None:
    assert value(expr, "REAL") == (expected, False)


@pytest.mark.parametrize(
    ("expr", "rtype", "expected"),
    [
        ("WORD_TO_INT(W#16#FFFF)", "INT", -1),
        ("INT_TO_WORD(-2)", "WORD", 0xFFFE),
        ("DWORD_TO_DINT(DW#16#8000_0000)", "DINT", -(2**31)),
        ("DWORD_TO_REAL(DW#16#3F80_0000)", "REAL", 1.0),
        ("REAL_TO_DWORD(-2.0)", "DWORD", 0xC000_0000),
        ("REAL_TO_INT(2.5)", "INT", 2),  # to the even number
        ("REAL_TO_INT(3.5)", "INT", 4),
        ("ROUND(-1.5)", "DINT", -2),
        ("TRUNC(-1.7)", "DINT", -1),
        ("BYTE_TO_WORD(B#16#7F)", "WORD", 0x7F),
        ("WORD_TO_BYTE(W#16#1234)", "BYTE", 0x34),
        ("BOOL_TO_BYTE(TRUE)", "BYTE", 1),
        ("CHAR_TO_INT('A')", "INT", 65),
        ("INT_TO_CHAR(66)", "CHAR", "B"),
        ("TIME_TO_DINT(T#1S)", "DINT", 1000),
        ("DINT_TO_TIME(2500)", "TIME", 2500),
        ("DATE_TO_DINT(D#1990-01-11)", "DINT", 10),
        ("TOD_TO_DINT(TOD#00:00:01)", "DINT", 1000),
        ("INT_TO_DINT(-5) * 100000", "DINT", -500000),
        ("INT_TO_REAL(3) / 2", "REAL", 1.5),
    ],
)
def test_conversion_functions(expr: str, rtype: str, expected: object) -> None:
    assert value(expr, rtype) == (expected, True)


@pytest.mark.parametrize(
    ("expr", "rtype", "expected"),
    [
        # the guide's table of shift and rotate (IN := 2#1101_0011)
        ("ROL(IN := BYTE#2#1101_0011, N := 5)", "BYTE", 0b0111_1010),
        ("ROR(IN := BYTE#2#1101_0011, N := 2)", "BYTE", 0b1111_0100),
        ("SHL(IN := BYTE#2#1101_0011, N := 3)", "BYTE", 0b1001_1000),
        ("SHR(IN := BYTE#2#1101_0011, N := 2)", "BYTE", 0b0011_0100),
        ("SHR(IN := W#16#F000, N := 12) AND 16#0007", "WORD", 7),
        ("NOT W#16#00FF", "WORD", 0xFF00),
        ("W#16#0F0F OR W#16#F000", "WORD", 0xFF0F),
        ("B#16#0F XOR B#16#FF", "BYTE", 0xF0),
        ("B#16#0F AND W#16#0FF0", "WORD", 0x0000),  # BYTE widened to WORD
    ],
)
def test_bit_functions_and_logic_on_bit_strings(expr: str, rtype: str, expected: int) -> None:
    assert value(expr, rtype) == (expected, True)


def test_numeric_functions() -> None:
    assert value("ABS(-5)", "INT") == (5, True)
    assert value("SQR(23)", "REAL") == (529.0, True)
    assert value("SQRT(81.0)", "REAL") == (9.0, True)
    assert value("EXPD(3)", "REAL") == (1000.0, True)
    assert value("LOG(100.0)", "REAL") == (2.0, True)
    got, ok = value("SIN(3.141592 / 6)", "REAL")
    assert ok and got == pytest.approx(0.5, abs=1e-6)
    got, _ = value("ACOS(0.5)", "REAL")
    assert got == pytest.approx(math.pi / 3, abs=1e-6)
    got, _ = value("LN(2.718281)", "REAL")
    assert got == pytest.approx(1.0, abs=1e-6)
    assert value("LIMIT(MN := 0, IN := 120, MX := 100)", "INT") == (100, True)
    assert value("MIN(4, -2, 7)", "INT") == (-2, True)
    assert value("MAX(IN1 := 1.5, IN2 := 2)", "REAL") == (2.0, True)
    assert value("SEL(G := TRUE, IN0 := 1, IN1 := 2)", "INT") == (2, True)
    assert value("MUX(K := 2, IN0 := 10, IN1 := 20, IN2 := 30)", "INT") == (30, True)
    assert value("MUX(5, 10, 20)", "INT") == (10, False)


@pytest.mark.parametrize(
    ("expr", "expected", "ok"),
    [
        ("CONCAT(IN1 := 'Motor', IN2 := ' 12')", "Motor 12", True),
        ("CONCAT('a', 'b', 'c')", "abc", True),
        ("LEFT(IN := 'Weldingstation', L := 7)", "Welding", True),
        ("RIGHT(L := 2, IN := I_STRNG(12))", "12", True),
        ("MID(IN := 'ABCDEF', L := 2, P := 3)", "CD", True),
        ("INSERT(IN1 := 'ABEF', IN2 := 'CD', P := 2)", "ABCDEF", True),
        ("DELETE(IN := 'ABCDEF', L := 2, P := 3)", "ABEF", True),
        ("REPLACE(IN1 := 'ABCDEF', IN2 := 'xy', L := 2, P := 2)", "AxyDEF", True),
        ("I_STRNG(-7)", "-7", True),
        ("R_STRNG(123.4567)", "+1.2345670E+02", True),
        ("LEFT(IN := 'abc', L := -1)", "", False),
        ("LEFT(IN := 'abc', L := 5)", "abc", True),  # L beyond the string: all of it
        ("RIGHT(IN := 'abc', L := 5)", "abc", True),
        ("RIGHT(IN := 'abcdef', L := 4)", "cdef", True),
        ("'$41$4E'", "AN", True),
    ],
)
def test_string_functions(expr: str, expected: str, ok: bool) -> None:
    assert value(expr, "STRING[40]") == (expected, ok)


def test_r_strng_of_an_infinity_or_nan_is_words_not_a_stop() -> None:
    assert value("R_STRNG(1.0 / z)", "STRING[20]", "z : REAL;")[0] == "+INF"
    assert value("R_STRNG(-1.0 / z)", "STRING[20]", "z : REAL;")[0] == "-INF"
    assert value("R_STRNG(z / z)", "STRING[20]", "z : REAL;")[0] == "NaN"


def test_string_functions_with_integer_results() -> None:
    assert value("LEN('Motor')", "INT") == (5, True)
    assert value("FIND(IN1 := 'ABCDEF', IN2 := 'CD')", "INT") == (3, True)
    assert value("FIND(IN1 := 'ABCDEF', IN2 := 'X')", "INT") == (0, True)
    assert value("STRNG_I('-123')", "INT") == (-123, True)
    assert value("STRNG_R('2.5')", "REAL") == (2.5, True)


def test_a_long_string_is_cut_to_its_variable_and_ok_is_cleared() -> None:
    assert value("s", "STRING[3]", "s : STRING[10] := 'abcdef';") == ("abc", False)


@pytest.mark.parametrize(
    ("expr", "rtype", "expected"),
    [
        ("INT#16#3F_FF", "INT", 0x3FFF),
        ("DINT#-1000_0000", "DINT", -10000000),
        ("WORD#8#177777", "WORD", 0xFFFF),
        ("W#2#1001_0100", "WORD", 0b1001_0100),
        ("B#(25, 25)", "WORD", 0x1919),
        ("REAL#1", "REAL", 1.0),
        ("4e2", "REAL", 400.0),
        ("BOOL#1", "BOOL", True),
        ("T#1H_20M_10S_30MS", "TIME", 4810030),
        ("TIME#24.5D", "TIME", 2116800000),
        ("T#25S", "S5TIME", 25000),  # a T# literal given to an S5TIME
        ("1", "BOOL", True),  # an untyped number adapts where it fits
        ("255", "BYTE", 255),
        ("100", "WORD", 100),
        ("16#FFFF", "DWORD", 0xFFFF),
        ("'A'", "CHAR", "A"),
        ("INT#5 * 2#11", "INT", 15),  # beside an INT, a number with a radix is an INT
        ("INT#5 = 8#5", "BOOL", True),
        ("INT#5 + 16#FFFF", "DINT", 65540),  # too big for an INT: a DINT
        ("WORD#16#F0 OR 15", "WORD", 0xFF),  # beside a WORD, a decimal number is a WORD
        ("CHAR#49", "CHAR", "1"),
        ("TOD#23:59:59.999", "TIME_OF_DAY", 86399999),
        ("TOD#23:00:00 + T#2H", "TOD", 3600000),
        ("TOD#10:00:00 - TOD#09:00:00", "TIME", 3600000),
        ("T#1S * 3", "TIME", 3000),
        ("T#10S / 4", "TIME", 2500),
    ],
)
def test_typed_literals_and_contextual_numbers(expr: str, rtype: str, expected: object) -> None:
    assert value(expr, rtype) == (expected, True)


def test_a_number_with_a_radix_counts_with_an_int_variable() -> None:
    src = """FUNCTION_BLOCK FB1
VAR i : INT; w : WORD; b : BOOL; END_VAR
  i := i + 16#1;
  b := i = 2#101;
  w := w AND 5;
END_FUNCTION_BLOCK
"""
    assert errors(src) == []


def test_date_and_time_arithmetic() -> None:
    got, ok = value("DT#1995-01-01-12:00:00 + T#1H", "DT")
    assert ok and (got.hour, got.minute) == (13, 0)
    assert value("D#1990-01-02 - D#1990-01-01", "TIME") == (86_400_000, True)
    assert value("DT#1995-01-01-12:00:01 - DT#1995-01-01-12:00:00", "TIME") == (1000, True)


@pytest.mark.parametrize(
    ("expr", "rtype", "expected"),
    [
        ("WORD_BCD_TO_INT(16#0123)", "INT", (123, True)),
        ("BCD_TO_INT(16#F123)", "INT", (-123, True)),  # the sign in bits 12-15
        ("WORD_BCD_TO_INT(16#012A)", "INT", (0, False)),  # A is no digit
        ("INT_TO_BCD_WORD(-123)", "WORD", (0xF123, True)),
        ("INT_TO_BCD(1000)", "WORD", (0, False)),  # three digits only
        ("DWORD_BCD_TO_DINT(16#F1234567)", "DINT", (-1234567, True)),
        ("DINT_TO_BCD_DWORD(1234567)", "DWORD", (0x01234567, True)),
        ("DINT_TO_BCD(10000000)", "DWORD", (0, False)),
    ],
)
def test_bcd_conversions_take_three_or_seven_digits_and_a_sign(
    expr: str, rtype: str, expected: tuple[int, bool]
) -> None:
    """S7-SCL's BCD conversions (the manual's CASE example reads a thumbwheel with
    ``WORD_BCD_TO_INT``): a digit A-F or a number beyond the digits clears OK."""
    assert value(expr, rtype) == expected


def test_a_date_beyond_the_s7_range_is_its_limit_with_ok_false() -> None:
    """DT runs from 1990-01-01 to 2089-12-31-23:59:59.999, DATE to 2168-12-31: a result
    beyond is the nearest limit and clears OK (AD_DT_TM limits its result and clears BR),
    never a stop of the CPU."""
    last = "t : DT := DT#2089-12-31-23:59:59;"
    got, ok = value("t + T#1S", "DT", last)
    assert not ok and (got.year, got.second, got.microsecond) == (2089, 59, 999000)
    got, ok = value("t - T#1S", "DT", last.replace("2089-12-31-23:59:59", "1990-01-01-0:0:0"))
    assert not ok and (got.year, got.month, got.day, got.hour) == (1990, 1, 1, 0)
    got, ok = value("DINT_TO_DATE(70000)", "DATE")
    assert not ok and (got.year, got.month, got.day) == (2168, 12, 31)
    got, ok = value("DINT_TO_DATE(-1)", "DATE")
    assert not ok and got.year == 1990


@pytest.mark.parametrize(
    ("body", "code"),
    [
        ("i := r;", "E220"),  # REAL to INT needs a function
        ("i := d;", "E220"),  # DINT to INT too
        ("w := i;", "E220"),  # INT to WORD too
        ("b := MW0 = 23;", "E221"),  # the guide: a WORD compared with an INT
        ("i := 'A' + 'B';", "E221"),
        ("b := (i <= 0) + (i > 0);", "E221"),
        ("i := 5 MOD 2.0;", "E221"),
        ("b := w < W#16#1;", "E221"),  # bit strings compare with = and <> only
        ("w := 70000;", "E220"),  # does not fit a WORD
        ("i := SHL(IN := i, N := 1);", "E220"),
        ("i := WORD_TO_INT(i);", "E220"),
        ("IF i THEN END_IF;", "E222"),
        ("i := nothing;", "E211"),
        ("i := LEFT(IN := 'a');", "E231"),
        ("i := ABS(X := 1);", "E230"),
        ("i := 99999999999;", "E203"),
        ("i := T#99999D;", "E203"),
    ],
)
def test_type_errors_are_located_diagnostics(body: str, code: str) -> None:
    src = f"""FUNCTION_BLOCK FB1
VAR i : INT; d : DINT; r : REAL; w : WORD; b : BOOL; END_VAR
  {body}
END_FUNCTION_BLOCK
"""
    assert errors(src) == [code]


@pytest.mark.parametrize("body", ["a := m;", "a := c;", "m := n;", "a := r;"])
def test_a_whole_array_is_assigned_only_to_one_of_the_same_bounds(body: str) -> None:
    """S7-SCL assigns a whole ARRAY when the element types and the bounds are the same —
    not merely the number of elements."""
    src = f"""FUNCTION_BLOCK FB1
VAR a : ARRAY[1..6] OF INT; c : ARRAY[0..5] OF INT; m : ARRAY[1..2, 1..3] OF INT;
  n : ARRAY[1..3, 1..2] OF INT; r : ARRAY[1..6] OF DINT; a2 : ARRAY[1..6] OF INT; END_VAR
  {body}
  a := a2;
END_FUNCTION_BLOCK
"""
    assert errors(src) == ["E220"]


def test_a_text_beyond_latin_1_is_refused_at_its_literal() -> None:
    """S7 strings hold one byte a character (latin-1): '€' is E203 where it is written,
    not a stop of the CPU when it is stored; '$80' writes the byte."""
    src = """FUNCTION_BLOCK FB1
VAR s : STRING[10] := 'uro'; c : CHAR; END_VAR
  s := 'é€';
  c := '$80';
END_FUNCTION_BLOCK
"""
    assert codes(src) == [("E203", 3, 8)]
    assert codes(src.replace(":= 'uro'", ":= '€uro'"))[0] == ("E203", 2, 23)


def test_a_string_break_leaves_out_the_layout_between_its_marks() -> None:
    """S7-SCL's string break: ``'ab$>`` and ``$<cd'`` on the next line are ``'abcd'``."""
    assert value("'ab$>\n     $<cd'", "STRING[10]") == ("abcd", True)
    assert value("'ab$>  $<cd'", "STRING[10]") == ("abcd", True)
    assert errors(
        "FUNCTION_BLOCK FB1\nVAR s : STRING[9]; END_VAR\n  s := 'ab$>x$<cd';\nEND_FUNCTION_BLOCK\n"
    ) == ["E203"]


def test_a_db_member_named_like_a_counter_is_a_member_a_variable_is_not() -> None:
    """``DB20.c1`` reads as the member c1 (only ``DB20.DW1`` is an address); a variable
    written alone as ``c1`` would be the counter C1 (E201)."""
    db = "DATA_BLOCK DB20\nSTRUCT c1 : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n"
    assert errors(db + "ORGANIZATION_BLOCK OB1\n  DB20.c1 := 3;\nEND_ORGANIZATION_BLOCK\n") == []
    assert errors("FUNCTION FC1 : VOID\nVAR_TEMP c1 : INT; END_VAR\n  c1 := 1;\nEND_FUNCTION\n")[
        :1
    ] == ["E201"]


def test_a_db_member_the_db_lacks_and_a_constant_division_by_zero_say_so() -> None:
    db = "DATA_BLOCK DB20\nSTRUCT a : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n"
    src = db + "ORGANIZATION_BLOCK OB1\n  DB20.b := 1;\nEND_ORGANIZATION_BLOCK\n"
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert [(d.code, d.message) for d in found] == [("E224", "DB20 has no member b; it has a")]
    src = "FUNCTION FC1 : VOID\nCONST N := 10 / 0; END_CONST\nEND_FUNCTION\n"
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert [(d.code, d.message) for d in found] == [("E217", "/ by zero in a constant expression")]


def test_a_real_constant_expression_beyond_the_real_range_is_E217() -> None:
    """``3.0E38 * 10.0`` in a CONST section is outside REAL, as a DINT constant beyond
    DINT is: a diagnostic at the expression, not an internal error."""
    src = "FUNCTION FC1 : VOID\nCONST BIG := 3.0E38 * 10.0; END_CONST\nEND_FUNCTION\n"
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert [(d.code, d.message, d.loc.line) for d in found] == [
        ("E217", "constant 3e+39 is outside REAL (±3.402823e+38)", 2)
    ]
    src = "FUNCTION FC1 : VOID\nCONST HALF := 1.0 / 3.0; END_CONST\nEND_FUNCTION\n"
    assert check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS) == []
