"""The uses of outside operands in an S7-SCL source (``steps/scl/xref.py``): what is listed
and what is a block's own, how each operand is spelt, and its access by where it stands —
an actual parameter by the called block's interface."""

from __future__ import annotations

from s7graph.steps.scl.parse import parse_source
from s7graph.steps.scl.xref import ARG_ACCESS, interfaces, scl_uses

SOURCE = """\
FUNCTION "Scale" : REAL
VAR_INPUT raw : INT; END_VAR
VAR_OUTPUT clipped : BOOL; END_VAR
VAR_IN_OUT count : INT; END_VAR
CONST K := 10; END_CONST
BEGIN
  clipped := raw > K;
  count := count + 1;
  "Scale" := INT_TO_REAL(raw) / 10.0;
END_FUNCTION

ORGANIZATION_BLOCK OB1
VAR_TEMP i : INT; x : REAL; END_VAR
BEGIN
  x := "Scale"(raw := %IW64, clipped := M0.1, count := "Counts");
  x := "Scale"(raw := IW66, clipped := M0.2, count := "Counts");
  FOR i := 1 TO "Data".n DO
    "Data".temps[i] := x;
  END_FOR;
  IF %I0.0 AND NOT T5 THEN
    FB17.DB10(IN := DB20.DBW4, OUT := MW8);
  END_IF;
  Motor_on := TRUE;
END_ORGANIZATION_BLOCK
"""


def _uses() -> list[tuple[str, str, str, int]]:
    source = parse_source(SOURCE, "test.scl")
    return [(u.operand, u.block, u.access, u.loc.line) for u in scl_uses(source)]


def test_only_outside_operands_are_listed_with_the_block_and_line_they_stand_in() -> None:
    uses = _uses()
    operands = {op for op, _, _, _ in uses}
    for own in ("raw", "clipped", "count", "K", "i", "x", "INT_TO_REAL"):
        assert not [u for u in operands if u.lstrip('"').startswith(own)], own
    assert ('"Scale"', 'FC "Scale"', "write", 9) in uses  # a function's return value
    assert ("MOTOR_ON", "OB 1", "write", 23) not in uses
    assert ("Motor_on", "OB 1", "write", 23) in uses  # an unquoted symbol, as written
    assert [u[3] for u in uses] == sorted(u[3] for u in uses)  # in the order written


def test_addresses_blocks_and_db_variables_are_spelt_one_way() -> None:
    uses = _uses()
    assert ("IW64", "OB 1", "argument", 15) not in uses  # the interface is known
    assert ("IW64", "OB 1", "read", 15) in uses and ("IW66", "OB 1", "read", 16) in uses
    assert ("I0.0", "OB 1", "read", 20) in uses and ("T5", "OB 1", "read", 20) in uses
    assert ('"Data".n', "OB 1", "read", 17) in uses
    assert ('"Data".temps', "OB 1", "write", 18) in uses  # members up to the first index
    assert ("FB 17", "OB 1", "call", 21) in uses and ("DB 10", "OB 1", "instance", 21) in uses


def test_an_actual_parameter_is_used_as_the_called_blocks_interface_declares_it() -> None:
    uses = _uses()
    assert ("M0.1", "OB 1", "write", 15) in uses and ("M0.2", "OB 1", "write", 16) in uses
    assert ('"Counts"', "OB 1", "read/write", 15) in uses
    assert ('"Scale"', "OB 1", "call", 15) in uses
    # FB17's interface is not in the source: its parameters' operands are arguments
    assert ("DB20.DBW4", "OB 1", "argument", 21) in uses
    assert ("MW8", "OB 1", "argument", 21) in uses
    source = parse_source(SOURCE, "test.scl")
    assert interfaces(source)["SCALE"] == {
        "RAW": "VAR_INPUT",
        "CLIPPED": "VAR_OUTPUT",
        "COUNT": "VAR_IN_OUT",
    }
    fb17 = {"FB17": {"IN": "VAR_INPUT", "OUT": "VAR_OUTPUT"}}
    given = [(u.operand, u.access) for u in scl_uses(source, fb17) if u.loc.line == 21]
    assert ("DB20.DBW4", "read") in given and ("MW8", "write") in given
    assert set(ARG_ACCESS) == {"VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "BLOCK_DB"}


def test_an_any_destination_of_a_system_block_is_written_and_its_source_read() -> None:
    """BLKMOV's DSTBLK and FILL's BLK are outputs (SFC 20, SFC 21), though the block takes
    them as pointer text; SRCBLK and BVAL are read — by name and by number alike."""
    from s7graph.sequencer.xref import block_references

    source = parse_source(
        """\
ORGANIZATION_BLOCK OB1
VAR_TEMP r : INT; END_VAR
BEGIN
  r := BLKMOV(SRCBLK := DB5.arr, DSTBLK := DB6.arr);
  r := FILL(BVAL := MW10, BLK := MW20);
  r := SFC20(SRCBLK := "Recipe".rec, DSTBLK := DB6.cur);
END_ORGANIZATION_BLOCK
""",
        "any.scl",
    )
    uses = {(u.operand, u.access) for u in block_references([source]).uses}
    assert {("DB5.arr", "read"), ("DB6.arr", "write")} <= uses
    assert {("MW10", "read"), ("MW20", "write")} <= uses
    assert {('"Recipe".rec', "read"), ("DB6.cur", "write")} <= uses


RECIPES = """\
FUNCTION FC5 : VOID
VAR_INPUT src : BLOCK_DB; x : INT; END_VAR
  MW12 := src.DW0;
END_FUNCTION

FUNCTION_BLOCK FB2
VAR_INPUT d : BLOCK_DB; END_VAR
  FC5(src := d, x := 1);
END_FUNCTION_BLOCK

ORGANIZATION_BLOCK OB1
BEGIN
  FC5(src := DB5, x := 1);
  FC5(src := "Recipe", x := MW2);
  FC5(src := DB 6, x := 2);
  FC5(src := WORD_TO_BLOCK_DB(MW4), x := 3);
  FC9(src := DB7, x := MW6);
END_ORGANIZATION_BLOCK
"""


def test_a_db_passed_as_a_whole_is_that_db_as_an_argument() -> None:
    """``DB5`` to any parameter, a symbol to a BLOCK_DB input: the DB, ``DB 5`` or
    ``"Recipe"``, *argument*; a DB's number as a WORD is read, and a BLOCK_DB parameter
    passed on is the block's own."""
    source = parse_source(RECIPES, "recipes.scl")
    assert interfaces(source)["FC5"] == {"SRC": "BLOCK_DB", "X": "VAR_INPUT"}
    uses = [(u.operand, u.access, u.loc.line) for u in scl_uses(source) if u.access != "call"]
    assert uses == [
        ("MW12", "write", 3),
        ("DB 5", "argument", 13),
        ('"Recipe"', "argument", 14),
        ("MW2", "read", 14),
        ("DB 6", "argument", 15),
        ("MW4", "read", 16),
        ("DB 7", "argument", 17),  # FC9's interface unknown: a DB all the same
        ("MW6", "argument", 17),
    ]


def test_a_projects_xref_groups_a_db_the_chart_and_its_blocks_pass() -> None:
    """A chart passing DB5 and an S7-SCL source passing it, by number or by the chart's
    symbol: one operand, ``"Recipe" (DB5)``, every use an *argument*; a DB of the symbol
    table likewise (``"Other" (DB6)``)."""
    from s7graph.engine.symbols import SymbolTable
    from s7graph.sequencer.text.parse import parse_chart
    from s7graph.sequencer.xref import cross_references

    chart = parse_chart(
        """FUNCTION_BLOCK "Seq" FB 1 DB 1
SYMBOLS "Recipe" : DB5 : DB5; END_SYMBOLS
PERMANENT BEFORE
  CALL FC 5 (src := DB5, x := 1);
  CALL FC 5 (src := "Other", x := 2);
END_PERMANENT
SEQUENCE 1 "S"
  INITIAL_STEP S1 "wait": END_STEP
END_SEQUENCE
END_FUNCTION_BLOCK
""",
        "seq.s7g",
    )
    table = SymbolTable.from_text('"Other" ; DB 6 ; DB 6\n')
    refs = cross_references(chart, table, [parse_source(RECIPES, "recipes.scl")])
    uses = {k: [(u.element, u.access, u.place) for u in v] for k, v in refs.operands().items()}
    assert uses['"Recipe" (DB5)'] == [
        ("permanent before 1", "argument", "seq.s7g:4:21"),
        ("OB 1", "argument", "recipes.scl:13:14"),
        ("OB 1", "argument", "recipes.scl:14:14"),
    ]
    assert uses['"Other" (DB6)'] == [
        ("permanent before 2", "argument", "seq.s7g:5:21"),
        ("OB 1", "argument", "recipes.scl:15:14"),
    ]
    assert uses["DB 7"] == [("OB 1", "argument", "recipes.scl:17:14")]
    assert refs.unused == ()
    assert [u.place for u in refs.of("db5")] == [u.place for u in refs.of('"Recipe"')]
