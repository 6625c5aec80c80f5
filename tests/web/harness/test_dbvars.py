"""DB variables by name for ``sim`` and ``run`` (``web/harness/dbvars.py``) in global DBs
written in S7-SCL: read in their types, written through their types, by number or by the
DB's name, and a name the DB lacks says what it has."""

from __future__ import annotations

import pytest

from s7graph import sfb
from s7graph.engine import Cpu, VirtualClock
from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import compile_scl
from s7graph.web.harness.dbvars import DbVariables

SOURCE = """
TYPE "Pump"
STRUCT on : BOOL; rpm : INT; END_STRUCT
END_TYPE
DATA_BLOCK DB20
STRUCT
  warm : BOOL; count : INT; mask : WORD; avg : REAL; wait : TIME;
  motor : ARRAY[1..3] OF STRUCT run : BOOL; speed : INT; END_STRUCT;
END_STRUCT
BEGIN count := -7; mask := 16#F00F; avg := 2.5; wait := T#1S500MS;
END_DATA_BLOCK
DATA_BLOCK "Data"
STRUCT temps : ARRAY[1..4] OF REAL; END_STRUCT
BEGIN temps[2] := 21.5;
END_DATA_BLOCK
DATA_BLOCK DB5 "Pump"
BEGIN rpm := 1450;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
VAR_TEMP info : ARRAY[0..19] OF BYTE; END_VAR
BEGIN
  DB20.warm := DB5.on;
  DB20.motor[2].speed := DB20.count * 2;
END_ORGANIZATION_BLOCK
"""


@pytest.fixture
def dbvars() -> DbVariables:
    program = compile_scl(SOURCE, "db.scl", blocks=sfb.SYSTEM_BLOCKS, names={"Data": "DB21"})
    cpu = Cpu(VirtualClock())
    sfb.install(cpu)
    program.load(cpu)
    cpu.start()
    return DbVariables(cpu, program.types)


def test_global_db_variables_read_in_their_types(dbvars: DbVariables) -> None:
    def read(name: str) -> object:
        return dbvars.reader(name)()

    assert read("DB20.warm") is False
    assert read("DB20.count") == -7 and read("DB20.mask") == 0xF00F
    assert read("DB20.avg") == 2.5 and read("DB20.wait") == 1500
    assert read('"Data".temps[2]') == 21.5 and read("DB21.temps[1]") == 0.0
    assert read("DB5.rpm") == 1450  # a DB of a UDT


def test_a_stimulus_writes_a_global_db_variable_the_program_reads(
    dbvars: DbVariables,
) -> None:
    dbvars.writer("DB5.on")(True)
    dbvars.writer("DB20.count")(-300)
    dbvars.writer('"Data".temps[4]')(-1.25)
    dbvars.cpu.scan()
    assert dbvars.reader("DB20.warm")() is True
    assert dbvars.reader("DB20.motor[2].speed")() == -600
    assert dbvars.reader("DB21.temps[4]")() == -1.25
    with pytest.raises(S7Error, match=r"DB20.count: .*32768"):
        dbvars.writer("DB20.count")(32768)


def test_a_stimulus_value_is_read_as_a_modify_reads_it(dbvars: DbVariables) -> None:
    """The text forms the command line promises for pins and variables hold for a DB's
    too (``"TRUE"``, ``"5"``, ``"T#5S"``, ``"16#FF"``); a value that does not fit is refused
    in words, naming the variable."""
    for name, given, read in [
        ("DB5.on", "TRUE", True),
        ("DB20.count", "5", 5),
        ("DB20.wait", "T#5S", 5000),
        ("DB20.mask", "16#FF", 0xFF),
    ]:
        dbvars.writer(name)(given)
        assert dbvars.reader(name)() == read, name
    with pytest.raises(S7Error) as caught:
        dbvars.writer("DB20.count")({"a": 1})
    assert caught.value.message.startswith("DB20.count: ") and "{" not in caught.value.message


def test_a_name_a_global_db_lacks_names_the_db_and_what_it_has(dbvars: DbVariables) -> None:
    with pytest.raises(S7Error) as caught:
        dbvars.reader("DB20.wram")
    assert str(caught.value) == (
        "DB20.wram: DB20 has no member wram; it has warm, count, mask, avg, wait, motor"
    )
    with pytest.raises(S7Error, match=r'"Oven".x: no DB is named "Oven"'):
        dbvars.reader('"Oven".x')
    with pytest.raises(S7Error, match=r"DB20.motor\[4\].run: index 4 outside 1..3"):
        dbvars.reader("DB20.motor[4].run")


def test_a_db_symbol_of_the_cpus_symbol_table_names_a_db(dbvars: DbVariables) -> None:
    table = SymbolTable.from_text('"Plant" ; DB 20 ; DB 20\n"Pumps" ; FB 3 ; FB 3\n')
    dbvars.cpu.mem.symbols = table
    assert dbvars.reader('"Plant".count')() == -7
    assert dbvars.reader('"Data".temps[2]')() == 21.5  # the DB's own name still holds
    dbvars.writer('"plant".motor[1].speed')(12)
    assert dbvars.reader("DB20.motor[1].speed")() == 12
    with pytest.raises(S7Error, match=r'^"Pumps".on: "Pumps" is FB 3, not a DB$'):
        dbvars.reader('"Pumps".on')


TIMED = """
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR tmr : TON; END_VAR
BEGIN
  tmr(IN := go, PT := T#2S);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
VAR_TEMP info : ARRAY[0..19] OF BYTE; END_VAR
BEGIN
  FB17.DB10(go := TRUE);
END_ORGANIZATION_BLOCK
"""


def test_a_system_blocks_multi_instance_reads_its_variables_never_its_python_state() -> None:
    program = compile_scl(TIMED, "t.scl", blocks=sfb.SYSTEM_BLOCKS)
    clock = VirtualClock()
    cpu = Cpu(clock)
    sfb.install(cpu)
    program.load(cpu)
    cpu.start()
    for _ in range(11):
        cpu.scan()
        clock.advance(100)
    dbvars = DbVariables(cpu, program.types)
    assert dbvars.reader("DB10.tmr")() == {"IN": True, "PT": 2000, "Q": False, "ET": 1000}
    assert dbvars.reader("DB10.tmr.ET")() == 1000
    with pytest.raises(S7Error, match=r"^DB10.tmr.STATE: SFB4 has no member STATE; it has IN,"):
        dbvars.reader("DB10.tmr.STATE")
