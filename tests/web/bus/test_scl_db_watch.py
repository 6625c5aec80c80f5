"""A global DB written in S7-SCL watched by name over a real zenoh bus (TCP on 127.0.0.1)
against a program of SCL blocks in this process (``web.wiring.program_edge``): its layout
came with the compiled DB, so ``DB20.warm``, ``DB20.motor[2].speed`` and ``"Data".temps[2]``
read in their types, and a name the DB lacks says what it has. The CPU's symbol table names
the DBs (``"Data" ; DB 21``): the source's ``DATA_BLOCK "Data"`` gets its number from it, and
``"Plant".warm`` reads DB20 by its symbol."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from s7graph import sfb
from s7graph.engine import Cpu, VirtualClock
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import compile_scl
from tests.web.bus.test_diag_watch import Rig, program_rig

pytestmark = pytest.mark.timeout(120)

SOURCE = """
DATA_BLOCK DB20
STRUCT
  warm : BOOL; count : INT; mask : WORD; avg : REAL; wait : TIME;
  grid : ARRAY[1..2, 1..3] OF INT;
  motor : ARRAY[1..3] OF STRUCT run : BOOL; speed : INT; END_STRUCT;
END_STRUCT
BEGIN count := -7; mask := 16#F00F; avg := 2.5; wait := T#1S500MS; motor[2].speed := 9;
  grid[2, 3] := -4;
END_DATA_BLOCK
DATA_BLOCK "Data"
STRUCT temps : ARRAY[1..4] OF REAL; END_STRUCT
BEGIN temps[2] := 21.5;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
VAR_TEMP info : ARRAY[0..19] OF BYTE; END_VAR
BEGIN
  DB20.warm := TRUE;
END_ORGANIZATION_BLOCK
"""

SYMBOLS = """\
"Data" ; DB 21 ; DB 21 ; recipe temperatures
"Plant" ; DB20 ; DB20
"Motor" ; FB 17 ; FB 17
"Start" ; I0.0 ; BOOL
"Gone" ; DB 99 ; DB 99
"""


@pytest.fixture
def rig() -> Iterator[Rig]:
    table = SymbolTable.from_text(SYMBOLS)
    program = compile_scl(SOURCE, "db.scl", blocks=sfb.SYSTEM_BLOCKS, symbols=table)
    clock = VirtualClock()
    cpu = Cpu(clock, max_cycle_ms=5000)
    cpu.mem.symbols = table
    sfb.install(cpu)
    program.load(cpu)
    with program_rig(cpu, clock) as made:
        yield made


def test_an_scl_global_db_is_watched_by_name_in_its_types(rig: Rig) -> None:
    asked = [
        "DB20.warm",
        "DB20.count",
        "DB20.mask",
        "DB20.avg",
        "DB20.wait",
        "DB20.grid[2, 3]",
        "DB20.motor[2].speed",
        "db20.MOTOR[3].run",
        '"Data".temps[2]',
        "DB21.temps[1]",
    ]
    got = {v.address: (v.value, v.type, v.error) for v in rig.watch(asked).values}
    assert got["DB20.warm"] == (True, "BOOL", "")
    assert got["DB20.count"] == (-7, "INT", "")
    assert got["DB20.mask"] == (0xF00F, "WORD", "")
    assert got["DB20.avg"] == (2.5, "REAL", "")
    assert got["DB20.wait"] == (1500, "TIME", "")
    assert got["DB20.grid[2, 3]"] == (-4, "INT", "")
    assert got["DB20.motor[2].speed"] == (9, "INT", "")
    assert got["db20.MOTOR[3].run"] == (False, "BOOL", "")
    assert got['"Data".temps[2]'] == (21.5, "REAL", "")
    assert got["DB21.temps[1]"] == (0.0, "REAL", "")


def test_a_name_an_scl_db_lacks_says_what_the_db_has(rig: Rig) -> None:
    asked = ["DB20.wram", "DB20.motor[4].run", "DB20.motor[2]", '"Nope".x', "DB20.count[1]"]
    got = {v.address: v.error for v in rig.watch(asked).values}
    assert got["DB20.wram"] == (
        "DB20 has no variable 'wram'; it has warm, count, mask, avg, wait, grid, motor"
    )
    assert got["DB20.motor[4].run"].startswith("DB20 has no variable 'motor[4].run'")
    assert got["DB20.motor[2]"] == "DB20.motor[2] is a STRUCT: watch one of its elements"
    assert got['"Nope".x'] == '"Nope": no DB has this name'
    assert got["DB20.count[1]"] == "DB20.count is no ARRAY: it takes no index"


def test_a_db_symbol_of_the_symbol_table_names_the_db_over_the_bus(rig: Rig) -> None:
    asked = ['"Plant".warm', "Plant.motor[2].speed", '"Motor".x', '"Start".x', '"Gone".x']
    got = {v.address: (v.value, v.error) for v in rig.watch(asked).values}
    assert got['"Plant".warm'] == (True, "")
    assert got["Plant.motor[2].speed"][1] != ""  # a DB symbol is quoted, as in S7-SCL
    assert got['"Motor".x'][1] == '"Motor" is FB 17, not a DB'
    assert got['"Start".x'][1] == '"Start" is the operand I0.0, not a DB'
    assert got['"Gone".x'][1] == "DB99 is not loaded"
