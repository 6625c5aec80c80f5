"""A DB chosen at run time (``WORD_TO_BLOCK_DB(w).DW[i]``, a BLOCK_DB parameter's
``p.DW[i]``), the ANY parameters of the system
blocks (SFC 20 BLKMOV, SFC 21 FILL) pointed at absolute operands and global DB variables,
``%DB5.DBW2``, and the parameter types s7graph refuses with what to write instead
(docs/scl.md, "Operands" and "Calls"; Siemens, S7-SCL V5.3 for S7-300/400, "Data types",
BLOCK_DB and the class B conversions; STEP7 comprehensive guide vol. 2, ch. 12, SFC 20/21)."""

from __future__ import annotations

import pytest

from s7graph import sfb
from s7graph.steps.scl import check_scl
from tests.steps.scl.helpers import build, codes, cpu_with, run

DBS = """
DATA_BLOCK DB5
STRUCT a : INT := 11; b : INT := 22; flags : BYTE := 16#05; END_STRUCT
BEGIN
END_DATA_BLOCK
DATA_BLOCK DB6
STRUCT a : INT := 33; b : INT := 44; flags : BYTE; END_STRUCT
BEGIN
END_DATA_BLOCK
"""

RUNTIME_DB = (
    DBS
    + """
FUNCTION_BLOCK FB1
VAR nr : WORD := 5; i : INT := 2; r1 : WORD; r2 : WORD; r3 : BYTE; bit : BOOL;
  sum : INT; k : INT;
END_VAR
  r1 := WORD_TO_BLOCK_DB(nr).DW[i];
  r2 := WORD_TO_BLOCK_DB(nr).DBW0;
  r3 := WORD_TO_BLOCK_DB(IN := nr).DB[4];
  bit := WORD_TO_BLOCK_DB(nr).DX[4, 2];
  WORD_TO_BLOCK_DB(INT_TO_WORD(6)).DW2 := 16#0101;
  FOR k := 5 TO 6 DO
    sum := sum + WORD_TO_INT(WORD_TO_BLOCK_DB(INT_TO_WORD(k)).DW[0]);
  END_FOR;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
)


def test_word_to_block_db_reads_and_writes_the_db_numbered_at_run_time() -> None:
    cpu = run(RUNTIME_DB)
    v = cpu.instance_db(1).values
    assert (v["r1"], v["r2"], v["r3"], v["bit"]) == (22, 11, 5, True)
    assert v["sum"] == 11 + 33  # DB5.DBW0, then DB6.DBW0: one statement, two DBs
    assert cpu.mem.get("DB6.DBW2") == 0x0101


@pytest.mark.parametrize(
    ("nr", "why"),
    [
        (7, "t.scl:15:12: DB7.DBW0: DB7 does not exist"),
        (0, "t.scl:15:12: invalid address DB/WORD: DB number 0 outside 1..65535"),
        (1, "t.scl:15:12: DB1.DBW0: DB1 is the instance DB of FB1"),
    ],
)
def test_word_to_block_db_of_a_db_without_bytes_is_a_located_block_error(nr: int, why: str) -> None:
    src = RUNTIME_DB.replace(
        "r1 := WORD_TO_BLOCK_DB(nr).DW[i];", f"nr := {nr}; r1 := WORD_TO_BLOCK_DB(nr).DW[0];"
    )
    cpu = run(src)
    assert str(cpu.mode) == "STOP"
    assert any(why in str(e) for e in cpu.diagnostics.since(0))


def test_word_to_block_db_takes_a_fixed_bit_as_dx_d_and_dbx_for_reads_and_writes() -> None:
    """The S7-SCL manual's absolute form, ``.DX4.2`` (``.D4.2``: no size prefix is a bit),
    and STL's ``.DBX4.2``, as a numbered DB takes them."""
    src = (
        DBS
        + """
FUNCTION_BLOCK FB1
VAR nr : WORD := 5; b0 : BOOL; b1 : BOOL; b2 : BOOL; END_VAR
  b0 := WORD_TO_BLOCK_DB(nr).DBX4.0;
  b1 := WORD_TO_BLOCK_DB(nr).d4.1;
  b2 := WORD_TO_BLOCK_DB(nr).DX4.2;
  WORD_TO_BLOCK_DB(INT_TO_WORD(6)).DBX4.7 := TRUE;
  WORD_TO_BLOCK_DB(INT_TO_WORD(6)).DX4.1 := b2;
  WORD_TO_BLOCK_DB(nr).D4.0 := FALSE;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    )
    cpu = run(src)
    v = cpu.instance_db(1).values
    assert (v["b0"], v["b1"], v["b2"]) == (True, False, True)  # DB5.flags = 16#05
    assert (cpu.mem.get("DB6.DBB4"), cpu.mem.get("DB5.DBB4")) == (0x82, 0x04)


@pytest.mark.parametrize(
    ("access", "code", "message"),
    [
        ("DX4.8", "E205", "WORD_TO_BLOCK_DB(…).DX4.8: bit 8 outside 0..7"),
        ("DBX4.1[2]", "E224", "is followed by an access: .DW[i], .DB[i], .DD[i], .DX[i, j]"),
    ],
)
def test_a_fixed_bit_of_a_db_chosen_at_run_time_is_checked_where_written(
    access: str, code: str, message: str
) -> None:
    src = RUNTIME_DB.replace(
        "r1 := WORD_TO_BLOCK_DB(nr).DW[i];", f"bit := WORD_TO_BLOCK_DB(nr).{access};"
    )
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert [(d.code, d.loc.line, d.loc.col) for d in found] == [(code, 15, 31)]
    assert message in found[0].message


@pytest.mark.parametrize(
    ("statement", "message"),
    [
        ("r1 := WORD_TO_BLOCK_DB(nr);", "is followed by an access: .DW[i]"),
        ("WORD_TO_BLOCK_DB(nr);", "is followed by an access"),
        ("r1 := WORD_TO_BLOCK_DB(nr).a;", "is followed by an access"),
        ("r1 := WORD_TO_BLOCK_DB(nr).DBX3;", "is followed by an access"),  # a bit: .DX[3, b]
        ("r1 := WORD_TO_BLOCK_DB(i).DW[0];", "cannot pass an INT to WORD"),
        ("r1 := WORD_TO_BLOCK_DB().DW0;", "WORD_TO_BLOCK_DB takes 1 parameter(s), not 0"),
    ],
)
def test_word_to_block_db_wrongly_used_is_a_located_error(statement: str, message: str) -> None:
    src = RUNTIME_DB.replace("r1 := WORD_TO_BLOCK_DB(nr).DW[i];", statement)
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert len(found) == 1 and found[0].code in ("E220", "E224", "E231")
    assert (found[0].loc.line, message in found[0].message) == (15, True)


@pytest.mark.parametrize("call", ["ABS(i)[2]", "ABS(i).foo", "LEN('x').y", "S_CU(C_NO := 1).q"])
def test_nothing_may_follow_a_function_call(call: str) -> None:
    src = f"FUNCTION_BLOCK FB1\nVAR i : INT; END_VAR\n  i := {call};\nEND_FUNCTION_BLOCK\n"
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert [d.code for d in found] == ["E224"]
    assert "nothing may follow a call of" in found[0].message
    assert found[0].loc.line == 3 and found[0].loc.col > 8  # at what follows the call


BLKMOV = """
TYPE UDT1 STRUCT speed : INT; on : BOOL; t : TIME; END_STRUCT END_TYPE
DATA_BLOCK DB5
STRUCT
  a : INT := 1;
  arr : ARRAY[0..3] OF INT := 1, 2, 3, 4;
  rec : UDT1;
  recs : ARRAY[1..3] OF UDT1;
END_STRUCT
BEGIN
  rec.speed := 1500; rec.t := T#5S; recs[2].speed := 7;
END_DATA_BLOCK
DATA_BLOCK DB6
STRUCT
  arr : ARRAY[0..3] OF INT;
  rec : UDT1;
  cur : UDT1;
  pat : WORD := 16#ABCD;
  filled : ARRAY[1..4] OF WORD;
END_STRUCT
BEGIN
END_DATA_BLOCK
FUNCTION_BLOCK FB1
VAR r1 : INT; r2 : INT; r3 : INT; r4 : INT; r5 : INT; r6 : INT; k : INT := 2; END_VAR
  r1 := BLKMOV(SRCBLK := DB5.arr, DSTBLK := DB6.arr);
  r2 := SFC20(SRCBLK := DB5.rec, DSTBLK := DB6.rec);
  r3 := BLKMOV(SRCBLK := DB5.recs[k], DSTBLK := DB6.cur);
  r4 := FILL(BVAL := DB6.pat, BLK := DB6.filled);
  r5 := BLKMOV(SRCBLK := MW10, DSTBLK := MW20);
  r6 := BLKMOV(SRCBLK := 'P#DB5.DBX0.0 INT 1', DSTBLK := MW30);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  MW10 := W#16#1234;
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""


def test_blkmov_and_fill_point_at_global_db_variables_and_operands() -> None:
    cpu = run(BLKMOV)
    v = cpu.instance_db(1).values
    assert [v[f"r{k}"] for k in range(1, 7)] == [0] * 6  # RET_VAL 0: no error
    get = cpu.mem.get
    assert [get(f"DB6.DBW{2 * k}") for k in range(4)] == [1, 2, 3, 4]  # DB6.arr
    assert (get("DB6.DBW8"), get("DB6.DBD12")) == (1500, 5000)  # DB6.rec: speed, t
    assert get("DB6.DBW16") == 7  # DB6.cur := DB5.recs[2], the element chosen at run time
    assert [get(f"DB6.DBW{26 + 2 * k}") for k in range(4)] == [0xABCD] * 4  # FILL
    assert (get("MW20"), get("MW30")) == (0x1234, 1)


@pytest.mark.parametrize(
    ("actual", "message"),
    [
        ("r1", "r1 is a variable of the block, held as a value"),
        ("5", "not the value of an expression (INT)"),
        ("k + 1", "not the value of an expression (INT)"),
    ],
)
def test_an_any_parameter_needs_bytes_to_point_at(actual: str, message: str) -> None:
    src = BLKMOV.replace("SRCBLK := MW10", f"SRCBLK := {actual}")
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert [(d.code, d.loc.line) for d in found] == [("E220", 29)]
    assert found[0].message.startswith("BLKMOV (SFC20): SRCBLK is an ANY pointer")
    assert message in found[0].message


def test_absolute_db_operands_take_the_percent_prefix() -> None:
    src = (
        DBS
        + """
ORGANIZATION_BLOCK OB1
  %DB5.DBW2 := INT_TO_WORD(77);
  %DB5.DBX4.1 := TRUE;
  %MW0 := %DB5.DBW0;
END_ORGANIZATION_BLOCK
"""
    )
    cpu = run(src)
    assert (cpu.mem.get("DB5.DBW2"), cpu.mem.get("DB5.DBX4.1"), cpu.mem.get("MW0")) == (
        77,
        True,
        11,
    )


@pytest.mark.parametrize(
    ("type_name", "instead"),
    [
        ("BLOCK_SDB", "no SDB is loaded"),
        ("ANY", "pass the data itself"),
        ("POINTER", "pass the data itself"),
        ("BLOCK_FC", "call the FC by name"),
    ],
)
def test_unsupported_parameter_types_say_what_to_write_instead(
    type_name: str, instead: str
) -> None:
    src = f"FUNCTION FC1 : VOID\nVAR_INPUT p : {type_name}; END_VAR\nEND_FUNCTION\n"
    assert codes(src) == [("E212", 2, 15)]
    message = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS)[0].message
    assert message.startswith(f"the parameter type {type_name} is not supported here: {instead}")


def test_only_the_any_pins_of_system_blocks_are_declared_as_pointer_text() -> None:
    """S7-SCL tells a system block's ANY pin by the type the catalogue declares it with
    (``sfb.catalogue.ANY_AS``): no pin of another type may be declared so."""
    from s7graph.sfb.catalogue import ANY_AS, CATALOGUE

    others = [
        f"{e.key}.{p.name}"
        for e in CATALOGUE
        for p in e.pins
        if p.type != "ANY" and "".join(p.type.split()).upper() == ANY_AS
    ]
    assert others == []


BLOCK_DB = (
    DBS
    + """
DATA_BLOCK "Data"
STRUCT x : INT := 55; y : INT := 1; z : BYTE; END_STRUCT
BEGIN
END_DATA_BLOCK
FUNCTION FC1 : INT
VAR_INPUT src : BLOCK_DB; i : INT; END_VAR
  src.DX4.7 := TRUE;
  src.DW[i] := INT_TO_WORD(WORD_TO_INT(src.DW[i]) + 1);
  FC1 := WORD_TO_INT(src.DW0) + WORD_TO_INT(src.DW[2]);
END_FUNCTION
FUNCTION_BLOCK FB1
VAR_INPUT db : BLOCK_DB; END_VAR
VAR r1 : INT; r2 : INT; r3 : INT; r4 : INT; bit : BOOL; nr : WORD := 6; END_VAR
  r1 := FC1(src := DB5, i := 0);
  r2 := FC1(src := WORD_TO_BLOCK_DB(nr), i := 2);
  r3 := FC1(src := db, i := 0);
  r4 := FC1(src := "Data", i := 0);
  bit := db.D4.0;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1(db := DB5);
END_ORGANIZATION_BLOCK
"""
)


def test_a_block_db_parameter_reaches_the_bytes_of_the_db_the_caller_passes() -> None:
    """``src : BLOCK_DB`` in VAR_INPUT takes ``DB5``, a DB's name, ``WORD_TO_BLOCK_DB(w)``
    or the caller's own BLOCK_DB, and reads and writes that DB as ``src.DW[i]``, ``src.DW0``,
    ``src.DX4.7`` (S7-SCL manual, "Data types", parameter types)."""
    cpu = run(BLOCK_DB, names={"Data": "DB7"})
    v = cpu.instance_db(1).values
    assert v["db"] == 5  # the instance holds the DB's number
    assert (v["r1"], v["r2"], v["r3"], v["r4"]) == (12 + 22, 33 + 45, 13 + 22, 56 + 1)
    assert v["bit"] is True  # DB5.flags = 16#05 | 16#80
    assert (cpu.mem.get("DB5.DBB4"), cpu.mem.get("DB6.DBB4"), cpu.mem.get("DB7.DBX4.7")) == (
        0x85,
        0x80,
        True,
    )


def test_a_block_db_parameter_of_another_source_still_takes_a_db() -> None:
    """A block compiled before (``--blocks``) keeps its BLOCK_DB input: the engine holds it
    as the WORD with the DB's number, marked BLOCK_DB."""
    lib = build(
        "FUNCTION FC1 : INT\nVAR_INPUT src : BLOCK_DB; END_VAR\n"
        "  FC1 := WORD_TO_INT(src.DW2);\nEND_FUNCTION\n"
    )
    fc1 = lib.block("FC1")
    assert [(v.type, v.comment) for v in fc1.interface] == [("WORD", "BLOCK_DB")]
    main = build(
        DBS + "ORGANIZATION_BLOCK OB1\n  MW0 := INT_TO_WORD(FC1(src := DB6));\n"
        "END_ORGANIZATION_BLOCK\n",
        blocks=[fc1],
    )
    cpu, _ = cpu_with(lib)
    main.load(cpu)
    cpu.start()
    cpu.scan()
    assert cpu.mem.get("MW0") == 44


@pytest.mark.parametrize(
    ("text", "code", "message"),
    [
        ("VAR d : BLOCK_DB; END_VAR", "E212", "a BLOCK_DB is an input: declare it in VAR_INPUT"),
        ("VAR_IN_OUT d : BLOCK_DB; END_VAR", "E212", "a BLOCK_DB is an input"),
        ("VAR_INPUT d : ARRAY[1..2] OF BLOCK_DB; END_VAR", "E212", "an ARRAY of BLOCK_DB"),
        ("VAR_INPUT d : BLOCK_DB := 5; END_VAR", "E216", "no initial value"),
        (
            "VAR_INPUT d : BLOCK_DB; END_VAR\n  r := FC1(src := nr, i := 0);",
            "E220",
            'src is a BLOCK_DB: pass a DB (DB10, "Data"), WORD_TO_BLOCK_DB(w) or a BLOCK_DB '
            "parameter, not a WORD",
        ),
        (
            "VAR_INPUT d : BLOCK_DB; END_VAR\n  r := FC1(src := FB1, i := 0);",
            "E220",
            "FB1 is no DB",
        ),
        (
            "VAR_INPUT d : BLOCK_DB; END_VAR\n  r := FC1(src := DB0, i := 0);",
            "E214",
            "DB0: a DB is numbered 1..65535",
        ),
        ("VAR_INPUT d : BLOCK_DB; END_VAR\n  nr := d.a;", "E224", "d is followed by an access"),
        ("VAR_INPUT d : BLOCK_DB; END_VAR\n  nr := d;", "E220", "cannot assign a BLOCK_DB"),
    ],
)
def test_a_block_db_parameter_wrongly_declared_or_passed_is_a_located_error(
    text: str, code: str, message: str
) -> None:
    src = BLOCK_DB.split("FUNCTION_BLOCK FB1")[0] + (
        f"FUNCTION_BLOCK FB2\nVAR r : INT; nr : WORD; END_VAR\n{text}\nEND_FUNCTION_BLOCK\n"
    )
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS, names={"Data": "DB7"})
    assert [d.code for d in found] == [code]
    assert message in found[0].message and found[0].loc.line > 20
