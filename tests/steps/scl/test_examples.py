"""The example algorithms of the S7-SCL chapter (STEP7 comprehensive guide vol. 2, ch. 13,
"Examples of programming in SCL") as blocks in a real CPU on the virtual clock."""

from __future__ import annotations

import struct

from s7graph.engine import CpuMode
from tests.steps.scl.helpers import run

AVERAGE = """
FUNCTION FC1 : VOID
VAR_TEMP
  k, i : INT;
  sum, avg : REAL;
END_VAR
VAR_INPUT
  n : INT;
END_VAR
BEGIN
  sum := 0;
  k := 4 * (n - 1);
  FOR i := 0 TO k BY 4 DO
    sum := sum + DWORD_TO_REAL(MD[i]);
  END_FOR;
  avg := sum / n;
  MD100 := REAL_TO_DWORD(avg);
END_FUNCTION

ORGANIZATION_BLOCK OB1
VAR_TEMP
END_VAR
  FC1(n := 10);
END_ORGANIZATION_BLOCK
"""


def test_average_of_n_reals_in_md0_and_up_goes_to_md100() -> None:
    def fill(cpu: object) -> None:
        for k in range(10):
            cpu.mem.markers[4 * k : 4 * k + 4] = struct.pack(">f", 1.5 * (k + 1))  # type: ignore[attr-defined]

    cpu = run(AVERAGE, before=fill)
    assert struct.unpack(">f", cpu.mem.markers[100:104])[0] == 8.25


BIT_COUNT = """
ORGANIZATION_BLOCK OB1
VAR_TEMP
  a, b, c, s, i : INT;
END_VAR
  a := WORD_TO_INT(IW0);
  s := 0;
  FOR i := 1 TO 16 DO
    b := a / 2;
    c := a - b * 2;
    s := s + c;
    a := b;
  END_FOR;
  MW0 := INT_TO_WORD(s);
END_ORGANIZATION_BLOCK
"""


def test_bit_counting_of_iw0_counts_the_closed_switches_into_mw0() -> None:
    def switches(cpu: object) -> None:
        cpu.mem.periph_in[0:2] = (0b0110_0001_1000_0101).to_bytes(2, "big")  # type: ignore[attr-defined]

    cpu = run(BIT_COUNT, before=switches)
    assert cpu.mem.get("MW0") == 6


SORT_AS_PRINTED = """
FUNCTION FC1 : VOID
VAR_TEMP
  temp1, i, low, swap : INT;
END_VAR
VAR_INPUT
  n : INT;
END_VAR
LABEL
  a001, a002;
END_LABEL
  i := 2 * n - 2;
  low := 0;
a002: swap := 0;
a001: low := low + 1;
  IF WORD_TO_INT(db1.dbw[i - 2]) > WORD_TO_INT(db1.dbw[i]) THEN
    temp1 := WORD_TO_INT(db1.dbw[i - 2]);
    db1.dbw[i - 2] := db1.dbw[i];
    db1.dbw[i] := INT_TO_WORD(temp1);
    swap := 1;
  ELSE
    i := i - 2;
  END_IF;
  IF i >= low THEN
    GOTO a001;
  END_IF;
  mw0 := INT_TO_WORD(i);
  IF swap <> 0 THEN
    GOTO a002;
  END_IF;
END_FUNCTION

DATA_BLOCK DB1
STRUCT
  v : ARRAY[0..9] OF INT := 7, -3, 12, 0, 5, 5, -8, 30, 1, 2;
END_STRUCT
BEGIN
END_DATA_BLOCK

ORGANIZATION_BLOCK OB1
  fc1(n := 10);
END_ORGANIZATION_BLOCK
"""


SORT = SORT_AS_PRINTED.replace(
    """  i := 2 * n - 2;
  low := 0;
a002: swap := 0;
a001: low := low + 1;""",
    """a002: swap := 0;
  i := 2 * n - 2;
  low := 2;
a001: ;""",
).replace("    i := i - 2;\n  END_IF;", "  END_IF;\n  i := i - 2;")
DATA = [7, -3, 12, 0, 5, 5, -8, 30, 1, 2]


def words(cpu: object) -> list[int]:
    data = cpu.mem.dbs[1].data  # type: ignore[attr-defined]
    return [int.from_bytes(data[2 * k : 2 * k + 2], "big", signed=True) for k in range(10)]


def test_sorting_db1_with_goto_loops_leaves_ten_ints_in_order() -> None:
    """The guide's bubble sort of DB1 with two GOTO loops, its pass bounds reset for each
    pass (the listing as printed keeps ``low`` and ``i`` from the pass before)."""
    assert "low := 2" in SORT and "a001: ;" in SORT
    cpu = run(SORT)
    assert cpu.mode is CpuMode.RUN
    assert words(cpu) == sorted(DATA)


def test_the_sorting_listing_as_printed_does_what_a_reading_of_it_does() -> None:
    """Every GOTO goes where the listing says: the result is that of a line-by-line
    reading of it (which stops before the words are in order)."""
    v, n = list(DATA), 10
    i, low = 2 * n - 2, 0
    swap = 1
    while swap:
        swap = 0
        while True:
            low += 1
            if v[(i - 2) // 2] > v[i // 2]:
                v[(i - 2) // 2], v[i // 2] = v[i // 2], v[(i - 2) // 2]
                swap = 1
            else:
                i -= 2
            if i < low:
                break
    cpu = run(SORT_AS_PRINTED)
    assert words(cpu) == v != sorted(DATA)
    assert cpu.mem.get("MW0") == i


INTEGRATOR = """
FUNCTION_BLOCK FB1 // Integral calculation
VAR_INPUT
  IN : REAL;
  RESET : BOOL;
  ENABLE : BOOL;
END_VAR
VAR_OUTPUT
  OUT : REAL;
  RESET_ACTIV : BOOL;
END_VAR
VAR
  OUT_LOW : REAL;
  LAST_IN : REAL;
  LAST_OUT : REAL;
  LAST_TIME : REAL;
  ACTUAL_TIME : REAL;
  X : REAL;
  n : INT;
END_VAR
  // Reset of values
  RESET_ACTIV := RESET;
  IF RESET = TRUE THEN
    OUT := 0.0;
    OUT_LOW := 0.0;
    LAST_OUT := 0.0;
    LAST_TIME := ACTUAL_TIME;
    ACTUAL_TIME := TIME_TO_DINT(TIME_TCK()) / 1000.0;
    X := 0.0;
    n := 0;
  ELSIF ENABLE = FALSE THEN
    n := 0;
  ELSE
    // First integral cycle
    IF n = 0 THEN
      ACTUAL_TIME := TIME_TO_DINT(TIME_TCK()) / 1000.0;
      LAST_TIME := ACTUAL_TIME;
      LAST_IN := IN;
      n := 1;
    ELSE
      ACTUAL_TIME := TIME_TO_DINT(TIME_TCK()) / 1000.0;
      // Overflow correction
      IF ACTUAL_TIME < LAST_TIME THEN
        X := (ACTUAL_TIME - LAST_TIME + 2147483.647) * (IN + LAST_IN) / 2;
      ELSE
        X := (ACTUAL_TIME - LAST_TIME) * (IN + LAST_IN) / 2;
      END_IF;
      LAST_TIME := ACTUAL_TIME;
      LAST_IN := IN;
      // Integral calculation
      LAST_OUT := OUT;
      OUT := LAST_OUT + X;
      OUT_LOW := (OUT - LAST_OUT) - X + OUT_LOW;
      IF OUT_LOW <> 0 THEN
        IF ABS(OUT / OUT_LOW) < 10000000 THEN
          LAST_OUT := OUT;
          OUT := OUT - OUT_LOW;
          OUT_LOW := (OUT - LAST_OUT) + OUT_LOW;
        END_IF;
      END_IF;
    END_IF;
  END_IF;
END_FUNCTION_BLOCK

ORGANIZATION_BLOCK OB1
  FB1.DB1(IN := MW10 * 0.5, RESET := M0.1, ENABLE := M0.0);
END_ORGANIZATION_BLOCK
"""


def test_the_integrator_sums_trapezoids_over_time_tck_and_resets() -> None:
    """IN = 2.0 for one second in 100 ms cycles integrates to 2.0; a rising input (the
    trapezoids of a ramp) to the area under it; RESET starts over."""
    src = INTEGRATOR.replace("MW10 * 0.5", "INT_TO_REAL(WORD_TO_INT(MW10)) * 0.5")

    def enable(cpu: object) -> None:
        cpu.mem.set("M0.0", True)  # type: ignore[attr-defined]
        cpu.mem.set("MW10", 4)  # type: ignore[attr-defined]

    cpu = run(src, 11, ms=100, before=enable)
    db = cpu.instance_db(1)
    assert abs(db["OUT"] - 2.0) < 1e-5
    cpu.mem.set("M0.1", True)
    cpu.scan()
    assert db["OUT"] == 0.0 and db["RESET_ACTIV"] is True


def test_the_integrator_of_a_ramp_is_the_area_of_the_triangle() -> None:
    """IN = t over 0..2 s: the trapezoids are exact, OUT = 2.0."""
    src = INTEGRATOR.replace("MW10 * 0.5", "INT_TO_REAL(WORD_TO_INT(MW10)) / 10.0")
    cpu = run(src, 0)
    cpu.mem.set("M0.0", True)
    for k in range(21):  # IN = k / 10 at t = k * 100 ms
        cpu.mem.set("MW10", k)
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert abs(cpu.instance_db(1)["OUT"] - 2.0) < 1e-5


OB80 = """
ORGANIZATION_BLOCK OB1
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB80
VAR_TEMP
  OB80_EV_CLASS : BYTE;     // 16#35, event class 3
  OB80_FLT_ID : BYTE;       // fault identification code
  OB80_PRIORITY : BYTE;     // 26
  OB80_OB_NUMBR : BYTE;     // 80
  OB80_RESERVED_1 : BYTE;
  OB80_RESERVED_2 : BYTE;
  OB80_ERROR_INFO : WORD;
  OB80_ERR_EV_CLASS : BYTE;
  OB80_ERR_EV_NUM : BYTE;
  OB80_OB_PRIORITY : BYTE;
  OB80_OB_NUM : BYTE;
  OB80_DATE_TIME : DATE_AND_TIME;
END_VAR
  IF OB80_FLT_ID = b#16#01 THEN
    m0.0 := true;
  ELSE
    m0.0 := false;
  END_IF;
  MB1 := OB80_OB_NUMBR;
END_ORGANIZATION_BLOCK
"""


def test_the_ob80_handler_sees_flt_id_1_when_the_cycle_time_is_exceeded() -> None:
    cpu = run(OB80, 2)
    assert cpu.mem.get("M0.0") is False
    cpu.clock.advance(200)  # type: ignore[attr-defined]
    cpu.scan()
    assert cpu.mode is CpuMode.RUN
    assert cpu.mem.get("M0.0") is True and cpu.mem.get("MB1") == 80


MESSAGES = """
DATA_BLOCK Messagetexts
STRUCT
  Index : int;
  textbuffer : array [0..19] of string[34];
  HW : array [1..5] of string[16];       // 5 different devices
  statuses : array [1..5] of string[12]; // 5 different statuses
END_STRUCT
BEGIN
  Index := 0;
  HW[1] := 'Motor';
  HW[2] := 'Valve';
  HW[3] := 'Press';
  HW[4] := 'Weldingstation';
  HW[5] := 'Burner';
  Statuses[1] := 'problem';
  Statuses[2] := 'started';
  Statuses[3] := 'temperature';
  Statuses[4] := 'repaired';
  Statuses[5] := 'maintained';
END_DATA_BLOCK

FUNCTION Textgenerator : bool
VAR_INPUT
  unit : int;   // index of the device text
  no : int;     // ID number of the device
  status : int;
  value : int;
END_VAR
VAR_TEMP
  text : string[34];
  i : int;
END_VAR
  // initialization of the temporary variables
  text := '';
  Textgenerator := true;
  Case unit of
    1..5 : case status of
             1..5 : text := concat(in1 := Messagetexts.HW[unit],
                                   in2 := right(l := 2, in := I_STRNG(no)));
                    text := concat(in1 := text, in2 := Messagetexts.statuses[status]);
                    if value <> 0 then
                      text := concat(in1 := text, in2 := I_STRNG(value));
                    end_if;
           else Textgenerator := false;
           end_case;
  else Textgenerator := false;
  end_case;
  i := Messagetexts.index;
  Messagetexts.textbuffer[i] := text;
  Messagetexts.index := (i + 1) mod 20;
END_FUNCTION

Organization_block OB1
Var_temp
  Opsy_ifx : array [0..20] of byte;
  error : BOOL;
End_var;
  if %M10.0 <> %M10.1 then
    error := Textgenerator(unit := word_to_int(MW0),
                           no := word_to_int(IW2),
                           status := word_to_int(MW2),
                           value := 0);
    %M10.1 := M10.0;
    M10.2 := error;
  end_if;
end_organization_block
"""


def test_the_message_generator_builds_motor_12_started_in_the_text_buffer() -> None:
    def press(cpu: object) -> None:
        mem = cpu.mem  # type: ignore[attr-defined]
        mem.set("MW0", 1)
        mem.set("MW2", 2)
        mem.periph_in[2:4] = (12).to_bytes(2, "big")
        mem.set("M10.0", True)

    cpu = run(MESSAGES, 2, before=press, names={"Messagetexts": "DB10", "Textgenerator": "FC10"})
    db = cpu.mem.dbs[10].data
    assert cpu.mem.get("DB10.DBW0") == 1  # the next free line
    text = db[4 : 4 + db[3]].decode("latin-1")
    assert text == "Motor12started"
    assert cpu.mem.get("M10.2") is True and cpu.mem.get("M10.1") is True


SETPOINT = """
ORGANIZATION_BLOCK OB100
  mw0 := INT_TO_WORD(400);
  mw2 := INT_TO_WORD(0);
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB35
VAR_TEMP
  a, b : INT;
END_VAR
  a := WORD_TO_INT(mw0);
  b := WORD_TO_INT(mw2) + 1;
  CASE b OF
    0..3600: a := a + 1;
    3601..7200: a := a;
    7201..9000: a := a - 2;
  ELSE
    stp();
  END_CASE;
  mw0 := INT_TO_WORD(a);
  mw2 := INT_TO_WORD(b);
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB1
END_ORGANIZATION_BLOCK
"""


def test_the_setpoint_ramp_in_ob35_rises_holds_falls_and_stops_the_cpu() -> None:
    """The guide's heat-treatment ramp, OB35 every second (its listing reads the elapsed
    seconds from MW2 but never counts them: here ``b`` counts)."""

    def every_second(cpu: object) -> None:
        cpu.interrupts.configure(35, 1000)  # type: ignore[attr-defined]

    cpu = run(SETPOINT, 0)
    cpu.stop()
    every_second(cpu)
    cpu.start()
    for _ in range(51):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert (cpu.mem.get("MW0"), cpu.mem.get("MW2")) == (405, 5)
    cpu.mem.set("MW2", 7200)
    for _ in range(10):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mem.get("MW0") == 403
    cpu.mem.set("MW2", 9000)
    for _ in range(10):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mode is CpuMode.STOP
