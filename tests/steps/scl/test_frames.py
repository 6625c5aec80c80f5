"""Block frames and declarations as S7-SCL V5 writes them: attributes, comments, PROGRAM,
instance DBs with values, aggregates passed and copied, strings, dates, a 1,000-line source
compiled in time (docs/scl.md, "Blocks and declarations")."""

from __future__ import annotations

import time
from datetime import datetime

from s7graph.engine import CpuMode
from tests.steps.scl.helpers import build, codes, run


def test_attributes_comments_program_and_an_empty_begin() -> None:
    src = """
{S7_blockview := 'big'}
PROGRAM FB1
TITLE = 'Main Process Control'
// This block controls all motors
KNOW_HOW_PROTECT
VERSION : '3.1'
AUTHOR : myname
NAME : Furnace
FAMILY : Motor
VAR_INPUT
  in2 {S7_server := 'alarm_archiv'; S7_a_type := 'ar_send'} : DWORD;
END_VAR
VAR n : INT; END_VAR
BEGIN;
  (* a comment
     over two lines *)
  n := n + 1; // counted
END_PROGRAM

ORGANIZATION_BLOCK OB1
TITLE = 'cycle'
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 3)
    assert cpu.instance_db(1)["n"] == 3


def test_an_instance_db_declared_with_values() -> None:
    src = """
FUNCTION_BLOCK FB17
VAR_INPUT limit : INT := 3; END_VAR
VAR_OUTPUT hit : BOOL; END_VAR
VAR n : INT; END_VAR
  n := n + 1;
  hit := n >= limit;
END_FUNCTION_BLOCK
DATA_BLOCK DB20 FB17
BEGIN
  limit := 2;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
  FB17.DB20();
  FB17.DB21();
  M0.0 := DB20.hit;
  M0.1 := DB21.hit;
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 2)
    assert (cpu.mem.get("M0.0"), cpu.mem.get("M0.1")) == (True, False)
    assert cpu.instance_db(20)["limit"] == 2 and cpu.instance_db(21)["limit"] == 3


def test_whole_arrays_and_structures_are_copied_not_shared() -> None:
    src = """
FUNCTION_BLOCK FB3
VAR
  SETPOINTS : ARRAY[0..127] OF INT;
  PROCVALS : ARRAY[0..127] OF INT;
  CRTLLR : ARRAY[1..3, 1..4] OF INT;
  CRTLLR_1 : ARRAY[1..4] OF INT := 1, 2, 3, 4;
  MEASVAL : STRUCT
    VOLTAGE : REAL;
    RESISTANCE : REAL;
    SIMPLEARR : ARRAY[1..2, 1..2] OF INT;
  END_STRUCT;
  PROCVAL : STRUCT
    VOLTAGE : REAL := 1.5;
    RESISTANCE : REAL;
    SIMPLEARR : ARRAY[1..2, 1..2] OF INT;
  END_STRUCT;
  AUXVAR : REAL;
END_VAR
  PROCVALS[5] := 7;
  SETPOINTS := PROCVALS;
  PROCVALS[5] := 8;
  CRTLLR[1, 4] := CRTLLR_1[4];
  CRTLLR[3, 1] := -1;
  MEASVAL := PROCVAL;
  MEASVAL.SIMPLEARR[1, 2] := 4;
  AUXVAR := PROCVAL.VOLTAGE;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB3.DB3();
END_ORGANIZATION_BLOCK
"""
    db = run(src).instance_db(3)
    assert db["SETPOINTS"][5] == 7 and db["PROCVALS"][5] == 8
    assert db["CRTLLR"][3] == 4 and db["CRTLLR"][8] == -1
    assert db["MEASVAL"]["VOLTAGE"] == 1.5 and db["MEASVAL"]["SIMPLEARR"] == [0, 4, 0, 0]
    assert db["PROCVAL"]["SIMPLEARR"] == [0, 0, 0, 0]
    assert db["AUXVAR"] == 1.5


def test_a_structure_is_assigned_and_passed_by_position_whatever_its_member_names() -> None:
    """Only the members' types and their order must match (Program Design for S7-300/400,
    the rule for whole STRUCT assignments): the target keeps its own member names."""
    src = """
TYPE UDT1 STRUCT a : INT; b : REAL; END_STRUCT END_TYPE
DATA_BLOCK DB20
STRUCT
  s1 : STRUCT x : INT; y : REAL; END_STRUCT;
  s2 : UDT1;
  rows : ARRAY[1..2] OF STRUCT p : INT; q : REAL; END_STRUCT;
  r : INT;
END_STRUCT
BEGIN
  s1.x := 4; s1.y := 2.5;
END_DATA_BLOCK
FUNCTION FC1 : INT
VAR_INPUT p : UDT1; END_VAR
  FC1 := p.a;
END_FUNCTION
ORGANIZATION_BLOCK OB1
VAR_TEMP t : STRUCT p : INT; q : REAL; END_STRUCT; END_VAR
  t := DB20.s1;
  DB20.s2 := t;
  DB20.rows[2] := DB20.s1;
  DB20.r := FC1(p := DB20.s1);
END_ORGANIZATION_BLOCK
"""
    mem = run(src).mem  # s1 at 0, s2 at 6, rows at 12 (6 bytes each), r at 24
    real = bytes.fromhex("40200000")  # 2.5
    assert mem.get("DB20.DBW6") == 4 and mem.dbs[20].data[8:12] == real
    assert mem.get("DB20.DBW18") == 4 and mem.dbs[20].data[20:24] == real
    assert mem.get("DB20.DBW24") == 4


def test_an_in_out_structure_must_have_the_parameters_member_names() -> None:
    """An in/out parameter is the variable itself, read and written by member name: a
    STRUCT of the same member types under other names is E220 at the call, not a stop."""
    src = """
TYPE UDT1 STRUCT a : INT; b : BOOL; END_STRUCT END_TYPE
TYPE UDT2 STRUCT x : INT; y : BOOL; END_STRUCT END_TYPE
FUNCTION FC13 : VOID
VAR_IN_OUT io : UDT1; END_VAR
  io.a := 2;
END_FUNCTION
FUNCTION_BLOCK FB1
VAR x : UDT2; ok : UDT1; END_VAR
  FC13(io := ok);
  FC13(io := x);
END_FUNCTION_BLOCK
"""
    assert codes(src) == [("E220", 11, 8)]  # FC13(io := x)


def test_strings_chars_and_dates_in_an_fc_and_an_fb() -> None:
    src = """
FUNCTION FC4 : STRING[20]
VAR_INPUT s : STRING[10]; c : CHAR; END_VAR
  FC4 := CONCAT(IN1 := s, IN2 := c);
END_FUNCTION
FUNCTION_BLOCK FB4
VAR
  DISPLAY_1 : STRING[50];
  STRUCTURE1 : STRUCT
    DISPLAY_2 : STRING[100];
    DISPLAY_3 : STRING[50] := 'other';
  END_STRUCT;
  TIME_1 : DATE_AND_TIME;
  TIME_3 : DATE_AND_TIME;
  r : STRING[20];
  lt, eq : BOOL;
END_VAR
  DISPLAY_1 := 'Error in module 1';
  IF DISPLAY_1 <> STRUCTURE1.DISPLAY_3 THEN
    DISPLAY_1 := STRUCTURE1.DISPLAY_3;
  END_IF;
  TIME_1 := DATE_AND_TIME#1995-01-01-12:12:12.2;
  TIME_3 := DT#1995-02-02-11:11:11;
  IF TIME_1 < TIME_3 THEN
    TIME_1 := TIME_3;
  END_IF;
  r := FC4(s := 'ab', c := 'Z');
  lt := 'ab' < 'b';
  eq := 'A' = CHAR#65;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB4.DB4();
END_ORGANIZATION_BLOCK
"""
    db = run(src).instance_db(4)
    assert db["DISPLAY_1"] == "other" and db["r"] == "abZ"
    assert db["TIME_1"] == datetime(1995, 2, 2, 11, 11, 11)
    assert db["lt"] is True and db["eq"] is True


def test_an_array_passed_to_an_fc_is_a_copy_and_an_in_out_array_is_the_callers() -> None:
    src = """
FUNCTION FC6 : INT
VAR_INPUT a : ARRAY[1..3] OF INT; END_VAR
VAR_IN_OUT b : ARRAY[1..3] OF INT; END_VAR
  a[1] := 100;
  b[1] := 100;
  FC6 := a[1] + a[2];
END_FUNCTION
FUNCTION_BLOCK FB6
VAR x, y : ARRAY[1..3] OF INT := 1, 2, 3; r : INT; END_VAR
  r := FC6(a := x, b := y);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB6.DB6();
END_ORGANIZATION_BLOCK
"""
    db = run(src).instance_db(6)
    assert db["x"] == [1, 2, 3] and db["y"] == [100, 2, 3] and db["r"] == 102


def test_a_global_db_of_bools_and_a_dt_laid_out_as_s7_lays_them_out() -> None:
    src = """
DATA_BLOCK DB5
STRUCT
  flags : ARRAY[0..9] OF BOOL;
  b : BOOL := TRUE;
  stamp : DATE_AND_TIME := DT#1995-01-01-12:00:00;
  n : INT := -2;
END_STRUCT
BEGIN
  flags[9] := TRUE;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
VAR_TEMP i : INT; END_VAR
  FOR i := 0 TO 9 DO
    IF DB5.flags[i] THEN MW0 := INT_TO_WORD(i); END_IF;
  END_FOR;
  DB5.flags[3] := DB5.b;
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    data = cpu.mem.dbs[5].data
    assert len(data) == 14 and data[0] == 0b0000_1000 and data[1] == 0b10
    assert data[2] == 1 and data[4:6] == bytes([0x95, 0x01])
    assert cpu.mem.get("DB5.DBW12") == 0xFFFE
    assert cpu.mem.get("MW0") == 9


def test_a_thousand_line_source_compiles_quickly_and_runs() -> None:
    from tests.steps.scl.test_frames import thousand_lines

    src = thousand_lines()
    assert len(src.splitlines()) > 1000
    build(src)  # the parser's tables, once
    start = time.perf_counter()
    program = build(src)
    spent = time.perf_counter() - start
    assert spent < 5.0, spent
    from tests.steps.scl.helpers import cpu_with

    cpu, _ = cpu_with(program)
    cpu.start()
    cpu.scan()
    assert cpu.mode is CpuMode.RUN


def thousand_lines(blocks: int = 20) -> str:
    """20 FBs of about 50 lines (IF, CASE, FOR, WHILE, arrays, strings) and an OB1."""
    parts = []
    for k in range(1, blocks + 1):
        parts.append(f"""
FUNCTION_BLOCK FB{k}
VAR_INPUT
  start : BOOL;
  setpoint : REAL;
  count : INT;
END_VAR
VAR_OUTPUT
  running : BOOL;
  total : DINT;
  avg : REAL;
END_VAR
VAR
  buffer : ARRAY[0..15] OF REAL;
  state : INT;
  index : INT;
  text : STRING[32];
END_VAR
VAR_TEMP
  i : INT;
  sum : REAL;
END_VAR
  IF start AND NOT running THEN
    running := TRUE;
    state := 1;
  ELSIF NOT start THEN
    running := FALSE;
    state := 0;
  END_IF;
  CASE state OF
    0: total := 0;
    1, 2: total := total + INT_TO_DINT(count);
       state := state + 1;
    3..9: state := 1;
  ELSE
    state := 0;
  END_CASE;
  buffer[index] := setpoint;
  index := (index + 1) MOD 16;
  sum := 0.0;
  FOR i := 0 TO 15 DO
    sum := sum + buffer[i];
  END_FOR;
  avg := sum / 16.0;
  WHILE i > 0 DO
    i := i - 4;
  END_WHILE;
  text := CONCAT(IN1 := 'FB', IN2 := I_STRNG({k}));
  IF avg > 100.0 THEN
    MW{2 * k} := INT_TO_WORD(REAL_TO_INT(avg));
  END_IF;
END_FUNCTION_BLOCK
""")
    calls = "\n".join(
        f"  FB{k}.DB{k}(start := M0.{k % 8}, setpoint := INT_TO_REAL(k), count := k);"
        for k in range(1, blocks + 1)
    )
    parts.append(f"""
ORGANIZATION_BLOCK OB1
VAR_TEMP k : INT; END_VAR
  k := WORD_TO_INT(MW100);
{calls}
END_ORGANIZATION_BLOCK
""")
    return "".join(parts)
