"""Block frames, declarations, calls of FBs, FCs, SFBs and SFCs in SCL syntax, EN/ENO and
OK, operands and symbols, DBs and UDTs, block errors (docs/scl.md, "Blocks and
declarations", "Calls", "Operands", "Run time")."""

from __future__ import annotations

import pytest

from s7graph.engine import Cpu, CpuMode, EventId, VirtualClock, parse_address
from s7graph.engine.blocks import FB, FC
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import SclError, check_scl, format_diagnostic
from tests.steps.scl.helpers import build, codes, errors, run

FB17 = """
FUNCTION_BLOCK FB17
VAR_INPUT
  FINALVAL : INT;   // input parameter
END_VAR
VAR_IN_OUT
  IQ1 : REAL;       // in/out parameter
END_VAR
VAR_OUTPUT
  CONTROL : BOOL;   // output parameter
END_VAR
VAR
  INDEX : INT;
END_VAR
  CONTROL := FALSE;
  FOR INDEX := 1 TO FINALVAL DO
    IQ1 := IQ1 * 2;
    IF IQ1 > 10000 THEN
      CONTROL := TRUE;
    END_IF;
  END_FOR;
END_FUNCTION_BLOCK

ORGANIZATION_BLOCK OB1
VAR_TEMP
  variable1 : REAL;
END_VAR
  variable1 := 3.0;
  FB17.DB10(FINALVAL := 10, IQ1 := variable1);
  MD4 := REAL_TO_DWORD(variable1);
  M0.0 := DB10.CONTROL;
  M0.1 := ENO;
END_ORGANIZATION_BLOCK
"""


def test_an_fb_call_with_its_instance_db_in_out_back_and_outputs_read_after() -> None:
    cpu = run(FB17)
    assert cpu.mem.get("MD4") == 0x4540_0000  # 3.0 * 2**10 = 3072.0
    assert cpu.mem.get("M0.0") is False and cpu.mem.get("M0.1") is True
    idb = cpu.instance_db(10)
    assert (idb["FINALVAL"], idb["INDEX"], idb["IQ1"]) == (10, 11, 3072.0)


def test_an_input_left_out_keeps_its_last_value() -> None:
    src = FB17.replace(
        "FB17.DB10(FINALVAL := 10, IQ1 := variable1);",
        """
  IF M1.0 THEN FB17.DB10(IQ1 := variable1);
  ELSE FB17.DB10(FINALVAL := 12, IQ1 := variable1); M1.0 := TRUE; END_IF;""",
    )
    cpu = run(src, 2)
    assert cpu.instance_db(10)["FINALVAL"] == 12
    assert cpu.mem.get("M0.0") is True  # 3.0 * 2**12 > 10000


DISTANCE = """
FUNCTION FC1 : REAL
VAR_INPUT
  X1, X2, Y1, Y2 : REAL;
END_VAR
BEGIN
  FC1 := SQRT((X2 - X1) ** 2 + (Y2 - Y1) ** 2);
END_FUNCTION

FUNCTION FC2 : VOID
VAR_INPUT
  X1, X2, Y1, Y2 : REAL;
END_VAR
VAR_OUTPUT
  D : REAL;
END_VAR
BEGIN
  D := SQRT((X2 - X1) ** 2 + (Y2 - Y1) ** 2);
END_FUNCTION

ORGANIZATION_BLOCK OB1
VAR_TEMP
  DISTANCE, D2, D3 : REAL;
END_VAR
  DISTANCE := FC1(X1 := 0.0, X2 := 3.0, Y1 := 0.0, Y2 := 4.0);
  FC2(X1 := 0.0, X2 := 6.0, Y1 := 0.0, Y2 := 8.0, D := D2);
  D3 := FC1(X1 := 1, X2 := 1, Y1 := 0, Y2 := 2) + 1.0;
  MD0 := REAL_TO_DWORD(DISTANCE);
  MD4 := REAL_TO_DWORD(D2);
  MD8 := REAL_TO_DWORD(D3);
END_ORGANIZATION_BLOCK
"""


def test_fc_with_a_function_value_and_a_void_fc_with_an_output() -> None:
    cpu = run(DISTANCE)
    got = [cpu.mem.read_as(parse_address(a), "REAL") for a in ("MD0", "MD4", "MD8")]
    assert got == [5.0, 10.0, 3.0]


def test_fc_in_out_and_ok_eno() -> None:
    src = """
FUNCTION FC5 : INT
VAR_IN_OUT
  acc : INT;
END_VAR
VAR_INPUT
  add : INT;
END_VAR
  acc := acc + add;
  FC5 := acc;
END_FUNCTION

ORGANIZATION_BLOCK OB1
VAR_TEMP
  a, r : INT;
END_VAR
  a := 32000;
  r := FC5(acc := a, add := 800);      // overflows: OK of FC5 false
  M0.0 := ENO;
  MW2 := INT_TO_WORD(a);
  a := 1;
  r := FC5(acc := a, add := 2);
  M0.1 := ENO;
  MW4 := INT_TO_WORD(r);
  FC5(EN := FALSE, acc := a, add := 100);
  M0.2 := ENO;
  MW6 := INT_TO_WORD(a);
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.mem.get("M0.0") is False and cpu.mem.get("M0.1") is True
    assert cpu.mem.read_as(parse_address("MW2"), "INT") == -32736
    assert cpu.mem.get("MW4") == 3
    assert cpu.mem.get("M0.2") is False and cpu.mem.get("MW6") == 3


def test_ok_can_be_set_read_and_becomes_eno() -> None:
    src = """
FUNCTION_BLOCK FB2
VAR_INPUT d : INT; END_VAR
VAR_OUTPUT q : INT; sawok : BOOL; END_VAR
  OK := TRUE;
  q := 100 / d;
  sawok := OK;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB2.DB2(d := 0);
  M0.0 := ENO;
  M0.1 := DB2.sawok;
  FB2.DB2(d := 4);
  M0.2 := ENO;
  FB2.DB2(EN := M9.0, d := 0);
  M0.3 := ENO;
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert [cpu.mem.get(f"M0.{k}") for k in range(4)] == [False, False, True, False]
    assert cpu.instance_db(2)["q"] == 25


EVALUATE_ACQUIRE = """
FUNCTION SQUARE : INT
VAR_INPUT
  value : INT;
END_VAR
BEGIN
  IF value <= 181 THEN
    SQUARE := value * value;   // calculation of the function value
  ELSE
    SQUARE := 32_767;          // if overflow, the maximum value
  END_IF;
END_FUNCTION

FUNCTION_BLOCK EVALUATE
CONST
  LIMIT := 7;
END_CONST
VAR_IN_OUT
  sortbuffer : ARRAY[0..LIMIT] OF INT;
END_VAR
VAR_OUTPUT
  calcbuffer : ARRAY[0..LIMIT] OF
  STRUCT
    root : INT;
    square : INT;
  END_STRUCT;
END_VAR
VAR_TEMP
  swap : BOOL;
  index, help : INT;
  valuer, resultno : REAL;
END_VAR
BEGIN
  REPEAT
    swap := FALSE;
    FOR index := LIMIT TO 1 BY -1 DO
      IF sortbuffer[index - 1] > sortbuffer[index] THEN
        help := sortbuffer[index];
        sortbuffer[index] := sortbuffer[index - 1];
        sortbuffer[index - 1] := help;
        swap := TRUE;
      END_IF;
    END_FOR;
  UNTIL NOT swap
  END_REPEAT;
  FOR index := 0 TO LIMIT BY 1 DO
    valuer := INT_TO_REAL(sortbuffer[index]);
    resultno := SQRT(valuer);
    calcbuffer[index].root := REAL_TO_INT(resultno);
    calcbuffer[index].square := SQUARE(sortbuffer[index]);
  END_FOR;
END_FUNCTION_BLOCK

FUNCTION_BLOCK ACQUIRE
CONST
  LIMIT := 7;
  NUMBER := LIMIT + 1;
END_CONST
VAR_INPUT
  measval_in : INT;
  newval : BOOL;
  resort : BOOL;
  funct_sel : BOOL;
  newsel : BOOL;
  selection : WORD;
END_VAR
VAR_OUTPUT
  result_out : INT;
  measval_out : INT;
END_VAR
VAR
  measvalues : ARRAY[0..LIMIT] OF INT := 8(0);
  resultbuffer : ARRAY[0..LIMIT] OF
  STRUCT
    root : INT;
    square : INT;
  END_STRUCT;
  Index : INT := 0;
  oldval : BOOL := TRUE;
  oldsort : BOOL := TRUE;
  oldsel : BOOL := TRUE;
  address : INT := 0;
  eval_instance : EVALUATE;
END_VAR
BEGIN
  IF newval <> oldval THEN
    Index := Index MOD NUMBER;
    measvalues[Index] := measval_in;
    Index := Index + 1;
  END_IF;
  oldval := newval;
  IF resort <> oldsort THEN
    Index := 0;
    eval_instance(sortbuffer := measvalues);
  END_IF;
  oldsort := resort;
  resultbuffer := eval_instance.calcbuffer;
  IF newsel <> oldsel THEN
    address := WORD_TO_INT(SHR(IN := selection, N := 12) AND 16#0007);
  END_IF;
  oldsel := newsel;
  IF funct_sel THEN
    result_out := resultbuffer[address].square;
  ELSE
    result_out := resultbuffer[address].root;
  END_IF;
  measval_out := measvalues[address];
END_FUNCTION_BLOCK

ORGANIZATION_BLOCK CYCLE
VAR_TEMP
  systemdata : ARRAY[0..20] OF BYTE;
END_VAR
BEGIN
  ACQUIRE.ACQUIRE_DATA(
    measval_in := WORD_TO_INT(Input),
    newval := "Input 0.0",
    resort := Sorting_switch,
    funct_sel := Function_switch,
    newsel := Coding_switch,
    selection := Coding);
  IF Output_switch THEN
    Output := INT_TO_WORD(ACQUIRE_DATA.result_out);
  ELSE
    Output := INT_TO_WORD(ACQUIRE_DATA.measval_out);
  END_IF;
END_ORGANIZATION_BLOCK
"""
SYMBOLS = """
"Coding" ; IW0 ; WORD
"Coding_switch" ; I0.7 ; BOOL
"Function_switch" ; I0.2 ; BOOL
"Input 0.0" ; I0.0 ; BOOL
"Input" ; IW2 ; WORD
"Output" ; QW4 ; WORD
"Output_switch" ; I0.3 ; BOOL
"Sorting_switch" ; I0.1 ; BOOL
"""
NAMES = {"ACQUIRE": "FB10", "ACQUIRE_DATA": "DB10", "EVALUATE": "FB20", "SQUARE": "FC41"}
NAMES["CYCLE"] = "OB1"


def test_the_guides_measured_value_program_with_a_multi_instance() -> None:
    """Eight values into the ring buffer, sorted by the multi-instance EVALUATE, the
    third one's square and root selected by the coding switches."""
    symbols = SymbolTable.from_text(SYMBOLS)
    cpu = run(EVALUATE_ACQUIRE, 0, names=NAMES, symbols=symbols)
    values = [49, 4, 100, 9, 1, 16, 200, 25]
    pi = cpu.mem.periph_in
    pi[0] = 0x83  # the switches as the FB's "old" values start: no edge yet
    cpu.scan()
    for v in values:
        pi[2:4] = v.to_bytes(2, "big")
        pi[0] ^= 0x01  # toggle "Input 0.0"
        cpu.scan()
    pi[0] ^= 0x02  # sort
    pi[0] |= 0x20  # coding: element 2 (bits 12..14 of IW0)
    pi[0] ^= 0x80  # read the coding
    cpu.scan()
    acquire = cpu.instance_db(10)
    assert acquire["measvalues"] == sorted(values)
    assert acquire["measval_out"] == 9 and cpu.mem.get("QW4") == 9
    pi[0] |= 0x0C  # output switch, square
    cpu.scan()
    assert cpu.mem.get("QW4") == 81
    pi[0] &= ~0x04  # root
    cpu.scan()
    assert cpu.mem.get("QW4") == 3
    calc = acquire["eval_instance"]["calcbuffer"]
    assert [c["square"] for c in calc][-1] == 32767  # 200 > 181


def test_system_blocks_by_name_and_an_sfb_with_its_instance() -> None:
    src = """
ORGANIZATION_BLOCK OB1
VAR_TEMP t : TIME; END_VAR
  t := TIME_TCK();
  MD0 := DINT_TO_DWORD(TIME_TO_DINT(t));
  SFB4.DB5(IN := I0.0, PT := T#100MS);
  M4.0 := DB5.Q;
  IF I0.1 THEN STP(); END_IF;
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 3, ms=60)
    assert cpu.mem.get("MD0") == 120
    cpu.mem.periph_in[0] = 1
    for _ in range(3):
        cpu.scan()
        cpu.clock.advance(60)  # type: ignore[attr-defined]
    assert cpu.mem.get("M4.0") is True
    cpu.mem.periph_in[0] = 2
    cpu.scan()
    assert cpu.mode is CpuMode.STOP


def test_absolute_and_indexed_operands_and_the_analog_maximum_case() -> None:
    src = """
ORGANIZATION_BLOCK OB1
VAR_TEMP
  mx, i : INT;
END_VAR
  mx := 0;
  FOR i := 0 TO 14 BY 2 DO
    IF WORD_TO_INT(piw[i + 252]) > mx THEN
      mx := WORD_TO_INT(piw[i + 252]);
    END_IF;
  END_FOR;
  db1.dbw0 := INT_TO_WORD(mx);
  CASE mx OF
    10000..11000: Q0.0 := true;
    11010..12000: Q0.1 := true;
  ELSE:
    Q0.0 := false;
    Q0.1 := false;
  END_CASE;
  FOR i := 0 TO 7 DO
    Q[i + 1, 0] := DB1.DX[2, i];
  END_FOR;
  DB1.DW[4] := W#16#BEEF;
  MB20 := DB1.DB4;
END_ORGANIZATION_BLOCK
DATA_BLOCK DB1
STRUCT
  mx : INT;
  bits : BYTE := B#16#A5;
  b2 : BYTE;
  w : WORD;
END_STRUCT
BEGIN
END_DATA_BLOCK
"""

    def analog(cpu: object) -> None:
        for k, v in enumerate([500, 10500, 3000, 9000, 0, 7, 8, 9]):
            cpu.mem.periph_in[252 + 2 * k : 254 + 2 * k] = v.to_bytes(2, "big")  # type: ignore[attr-defined]

    cpu = run(src, 1, before=analog)
    assert cpu.mem.get("DB1.DBW0") == 10500
    assert cpu.mem.get("Q0.0") is True and cpu.mem.get("Q0.1") is False
    assert [cpu.mem.get(f"Q{k + 1}.0") for k in range(8)] == [bool(0xA5 >> k & 1) for k in range(8)]
    assert cpu.mem.get("MB20") == 0xBE


def test_the_archive_shifts_db_words_down_with_a_negative_step() -> None:
    src = """
ORGANIZATION_BLOCK OB35
VAR_TEMP
  m1, i : INT;
END_VAR
  m1 := word_to_int(piw260) / 10;
  db1.dbw0 := INT_TO_WORD(m1);
  FOR i := 18 TO 2 BY -2 DO
    db1.dbw[i] := db1.dbw[i - 2];
  END_FOR;
END_ORGANIZATION_BLOCK
ORGANIZATION_BLOCK OB1
END_ORGANIZATION_BLOCK
DATA_BLOCK DB1
STRUCT rows : ARRAY[1..10] OF INT; END_STRUCT
BEGIN
END_DATA_BLOCK
"""
    cpu = run(src, 0)
    for k in range(1, 4):
        cpu.mem.periph_in[260:262] = (k * 100).to_bytes(2, "big")
        for _ in range(10):
            cpu.clock.advance(10)  # type: ignore[attr-defined]
            cpu.scan()
    data = cpu.mem.dbs[1].data
    assert [int.from_bytes(data[2 * r : 2 * r + 2], "big") for r in range(5)] == [30, 30, 20, 10, 0]


def test_a_udt_a_db_of_it_and_structured_db_access() -> None:
    src = """
TYPE MEASVALUES
STRUCT
  BIPOL_1 : INT := 5;
  BIPOL_2 : WORD := W#16#FFAA;
  BIPOL_3 : BYTE := B#16#F1;
  BIPOL_4 : WORD := B#(25, 25);
  MEASURE : STRUCT
    BIPOLAR_10V : REAL;
    UNIPOLAR_4_20MA : REAL;
  END_STRUCT;
END_STRUCT
END_TYPE

DATA_BLOCK DB11 MEASVALUES
BEGIN
  MEASURE.UNIPOLAR_4_20MA := 2.7;
END_DATA_BLOCK

FUNCTION_BLOCK FB10
VAR MEAS_RANGE : MEASVALUES; copy : MEASVALUES; END_VAR
  MEAS_RANGE.BIPOL_1 := MEAS_RANGE.BIPOL_1 - 9;
  MEAS_RANGE.MEASURE.UNIPOLAR_4_20MA := DB11.MEASURE.UNIPOLAR_4_20MA;
  copy := DB11;
  DB11.BIPOL_1 := MEAS_RANGE.BIPOL_1;
END_FUNCTION_BLOCK

ORGANIZATION_BLOCK OB1
  FB10.DB10();
END_ORGANIZATION_BLOCK
"""
    with pytest.raises(SclError):
        build(src)  # copy := DB11: a DB is not a variable of a UDT
    src = src.replace("copy := DB11;", "")
    cpu = run(src)
    meas = cpu.instance_db(10)["MEAS_RANGE"]
    assert meas["BIPOL_1"] == -4 and meas["BIPOL_2"] == 0xFFAA
    assert meas["MEASURE"]["UNIPOLAR_4_20MA"] == pytest.approx(2.7)
    assert cpu.mem.dbs[11].data[0:2] == (-4 & 0xFFFF).to_bytes(2, "big")
    assert cpu.mem.get("DB11.DBW6") == 0x1919


def test_every_element_of_an_array_of_structures_takes_their_initial_values() -> None:
    """Wherever a UDT or a STRUCT is used — alone, as the element of an ARRAY, in an FB's
    instance DB or a global DB — its members start at their ``:= …``."""
    src = """
TYPE UDT5 STRUCT on : BOOL := TRUE; sp : INT := 7; END_STRUCT END_TYPE
DATA_BLOCK DB20
STRUCT
  one : UDT5;
  arr : ARRAY[1..2] OF UDT5;
  st : ARRAY[1..2] OF STRUCT a : INT := 5; END_STRUCT;
END_STRUCT
BEGIN
END_DATA_BLOCK
FUNCTION_BLOCK FB1
VAR au : ARRAY[1..2] OF UDT5; END_VAR
  ;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.instance_db(1)["au"] == [{"on": True, "sp": 7}] * 2
    # one at 0 (BOOL, INT: 4 bytes), arr at 4 (4 bytes each), st at 12 (2 bytes each)
    assert [cpu.mem.get(f"DB20.DBX{n}.0") for n in (0, 4, 8)] == [True] * 3
    assert [cpu.mem.get(f"DB20.DBW{n}") for n in (2, 6, 10, 12, 14)] == [7, 7, 7, 5, 5]


def test_an_index_out_of_bounds_is_a_located_block_error_ob121_else_stop() -> None:
    src = """
FUNCTION_BLOCK FB1
VAR a : ARRAY[1..3] OF INT; i : INT; END_VAR
  i := 4;
  a[i] := 1;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.mode is CpuMode.STOP
    entry = next(e for e in cpu.diagnostics if e.block == "FB1")
    assert "t.scl:5:5: array index 4 outside 1..3" in entry.message
    with_121 = src + "\nORGANIZATION_BLOCK OB121\n  M0.0 := TRUE;\nEND_ORGANIZATION_BLOCK\n"
    cpu = run(with_121)
    assert cpu.mode is CpuMode.RUN and cpu.mem.get("M0.0") is True
    faulting = with_121.replace("M0.0 := TRUE;", "MW0 := DB7.DBW2;")  # OB121 faults too
    cpu = run(faulting)
    assert cpu.mode is CpuMode.STOP
    assert any(e.message.endswith("programming error, in OB121") for e in cpu.diagnostics)


def test_a_missing_db_is_a_located_block_error() -> None:
    src = "ORGANIZATION_BLOCK OB1\n  MW0 := DB7.DBW2;\nEND_ORGANIZATION_BLOCK\n"
    cpu = run(src)
    assert cpu.mode is CpuMode.STOP
    assert any("t.scl:2:3" in e.message and "DB7" in e.message for e in cpu.diagnostics)


def test_blocks_defined_outside_are_called_by_label() -> None:
    from s7graph.engine import fb, fc

    @fc(7, "DOUBLE", IN={"x": "INT"}, RET="INT")
    def double(ctx: object, p: dict[str, object]) -> object:
        return 2 * p["x"]  # type: ignore[operator]

    @fb(8, "KEEP", IN={"x": "INT"}, OUT={"y": "INT"})
    def keep(ctx: object, db: object) -> None:
        db["y"] = db["x"] + 1  # type: ignore[index]

    src = """
ORGANIZATION_BLOCK OB1
  MW0 := INT_TO_WORD(DOUBLE(x := 21));
  FB8.DB8(x := 41);
  MW2 := INT_TO_WORD(DB8.y);
END_ORGANIZATION_BLOCK
"""
    program = build(src, blocks=[double, keep])
    assert isinstance(double, FC) and isinstance(keep, FB)
    cpu = Cpu(VirtualClock())
    cpu.load(double, keep)
    program.load(cpu)
    cpu.start()
    cpu.scan()
    assert (cpu.mem.get("MW0"), cpu.mem.get("MW2")) == (42, 42)


def test_an_scl_block_is_called_from_python_through_the_engine() -> None:
    src = """
FUNCTION FC3 : INT
VAR_INPUT a, b : INT; END_VAR
VAR_OUTPUT s : INT; END_VAR
  s := a - b;
  FC3 := a + b;
END_FUNCTION
"""
    from s7graph.engine import ob
    from tests.steps.scl.helpers import cpu_with

    got: list[object] = []

    @ob(1)
    def main(ctx: object) -> None:
        got.append(ctx.call("FC3", a=5, b=3, s=None))  # type: ignore[attr-defined]

    cpu, _ = cpu_with(build(src))
    cpu.load(main)
    cpu.start()
    cpu.scan()
    assert got == [{"s": 2, "RET_VAL": 8}]


@pytest.mark.parametrize(
    ("src", "code"),
    [
        ("FUNCTION FC1 : VOID VAR x : INT; END_VAR END_FUNCTION", "E215"),
        ("ORGANIZATION_BLOCK OB1 VAR_INPUT x : INT; END_VAR END_ORGANIZATION_BLOCK", "E215"),
        ("FUNCTION_BLOCK Motor END_FUNCTION_BLOCK", "E214"),
        ("FUNCTION_BLOCK FC3 END_FUNCTION_BLOCK", "E213"),
        ("FUNCTION_BLOCK FB1 VAR x : INT; X : BOOL; END_VAR END_FUNCTION_BLOCK", "E210"),
        ("FUNCTION_BLOCK FB1 END_FUNCTION_BLOCK FUNCTION_BLOCK FB1 END_FUNCTION_BLOCK", "E210"),
        ("FUNCTION_BLOCK FB1 VAR x : WIDGET; END_VAR END_FUNCTION_BLOCK", "E212"),
        ("FUNCTION_BLOCK FB1 VAR x : ARRAY[3..1] OF INT; END_VAR END_FUNCTION_BLOCK", "E217"),
        ("FUNCTION_BLOCK FB1 VAR x : STRING[300]; END_VAR END_FUNCTION_BLOCK", "E217"),
        ("FUNCTION_BLOCK FB1 VAR x : INT := 1.5; END_VAR END_FUNCTION_BLOCK", "E216"),
        ("FUNCTION_BLOCK FB1 VAR_TEMP x : INT := 1; END_VAR END_FUNCTION_BLOCK", "E216"),
        ("FUNCTION FC1 : INT END_FUNCTION", "E243"),
        ("FUNCTION_BLOCK FB1 CONST c := 1; END_CONST c := 2; END_FUNCTION_BLOCK", "E223"),
        ("FUNCTION_BLOCK FB1 FB9.DB9(); END_FUNCTION_BLOCK", "E213"),
        ("FUNCTION_BLOCK FB1 FB1(); END_FUNCTION_BLOCK", "E233"),
        (
            "FUNCTION_BLOCK FB1 VAR_INPUT x : INT; END_VAR FB1.DB2(y := 1); END_FUNCTION_BLOCK",
            "E230",
        ),
        (
            "FUNCTION FC1 : INT VAR_INPUT x : INT; END_VAR FC1 := 1; END_FUNCTION "
            "FUNCTION_BLOCK FB1 VAR i : INT; END_VAR i := FC1(); END_FUNCTION_BLOCK",
            "E231",
        ),
        (
            "FUNCTION FC1 : VOID VAR_OUTPUT q : INT; END_VAR q := 1; END_FUNCTION "
            "FUNCTION_BLOCK FB1 VAR i : INT; END_VAR i := 1 + FC1(q := i); END_FUNCTION_BLOCK",
            "E232",
        ),
        ("FUNCTION_BLOCK FB1 VAR b : BOOL; END_VAR b := M0.8; END_FUNCTION_BLOCK", "E205"),
        (
            "FUNCTION_BLOCK FB1 VAR a : ARRAY[1..2] OF INT; END_VAR a[3] := 1; END_FUNCTION_BLOCK",
            "E225",
        ),
        (
            "FUNCTION_BLOCK FB1 VAR a : ARRAY[1..2] OF INT; END_VAR a[1, 2] := 1; END_FUNCTION_BLOCK",  # noqa: E501
            "E224",
        ),
        ("FUNCTION_BLOCK FB1 VAR i : INT; END_VAR i.x := 1; END_FUNCTION_BLOCK", "E224"),
        ("FUNCTION_BLOCK FB1 VAR i : INT; END_VAR ABS(i); END_FUNCTION_BLOCK", "E232"),
    ],
)
def test_declaration_and_call_diagnostics(src: str, code: str) -> None:
    assert code in errors(src), codes(src)


def test_unknown_variable_is_located_at_its_name() -> None:
    src = "FUNCTION_BLOCK FB1\nVAR i : INT; END_VAR\n  i := i + speed;\nEND_FUNCTION_BLOCK\n"
    found = check_scl(src, "m.scl")
    assert [(d.code, d.loc.line, d.loc.col, d.element) for d in found] == [("E211", 3, 12, "FB1")]
    assert "'speed'" in found[0].message


def test_block_errors_still_go_to_ob121_with_its_start_info() -> None:
    src = """
ORGANIZATION_BLOCK OB1
  MW0 := DB99.DBW0;
END_ORGANIZATION_BLOCK
ORGANIZATION_BLOCK OB121
VAR_TEMP OB121_SW_FLT : BYTE; END_VAR
  MB10 := OB121_SW_FLT;
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.mode is CpuMode.RUN
    assert cpu.mem.get("MB10") == EventId.AREA_ERROR & 0xFF


INSTANCE = """FUNCTION_BLOCK FB3
VAR acc : INT := 1000; s : STRUCT p : INT; q : INT := 4; END_STRUCT; a : ARRAY[1..3] OF INT;
END_VAR
  acc := acc + 1;
END_FUNCTION_BLOCK

DATA_BLOCK DB10 FB3
BEGIN
  {body}
END_DATA_BLOCK

ORGANIZATION_BLOCK OB1
  FB3.DB10();
END_ORGANIZATION_BLOCK
"""


def test_an_instance_dbs_begin_sets_members_and_elements_too() -> None:
    """``s.p := 7;`` and ``a[2] := 9;`` in an instance DB's BEGIN, as in a global DB's:
    the rest of the STRUCT and the ARRAY keep their initial values."""
    values = run(INSTANCE.format(body="acc := 5; s.p := 7; a[2] := 9;")).instance_db(10).values
    assert values["acc"] == 6 and values["s"] == {"p": 7, "q": 4} and values["a"] == [0, 9, 0]


def test_a_name_the_fb_lacks_in_an_instance_dbs_begin_is_an_error_where_it_is_written() -> None:
    assert codes(INSTANCE.format(body="acc := 5;\n  s.x := 7;")) == [("E224", 10, 5)]


def test_an_fb_called_without_an_instance_says_how_an_fb_is_called() -> None:
    src = """FUNCTION_BLOCK FB3
VAR_INPUT a : INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION FC4 : VOID
  FB3(a := 1);
END_FUNCTION
"""
    assert [format_diagnostic(d) for d in check_scl(src, "t.scl")] == [
        "t.scl:5:3: error[E233]: FB3 is a function block: call it with its instance DB,"
        " FB3.DB10(…), or as a multi-instance declared in VAR (FC4)"
    ]
