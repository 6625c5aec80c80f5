"""A global DB compiled from S7-SCL carries its layout (``steps/scl/layout.py``): every
variable's name, S7 type and place — the places the compiler's own access uses — into
the CPU's DB, for the readers that know no S7-SCL (the bus's watch)."""

from __future__ import annotations

from s7graph.engine.datatypes import Slot, decode
from s7graph.steps.scl.access import member, parse_name
from tests.steps.scl.helpers import build, cpu_with

DB = """
TYPE "Pump"
STRUCT on : BOOL; rpm : INT; END_STRUCT
END_TYPE
DATA_BLOCK DB20
STRUCT
  warm : BOOL; ready : BOOL; avg : REAL; count : INT; mask : WORD; wait : TIME;
  flags : ARRAY[0..9] OF BOOL;
  grid : ARRAY[1..2, 1..3] OF INT;
  motor : ARRAY[1..3] OF STRUCT run : BOOL; speed : INT; END_STRUCT;
  recipe : STRUCT speed : DINT; name : STRING[6]; END_STRUCT;
  pump : "Pump";
END_STRUCT
BEGIN avg := 2.5; count := -7; mask := 16#F00F; wait := T#1S500MS; motor[3].speed := 9;
END_DATA_BLOCK
DATA_BLOCK DB5 "Pump"
BEGIN rpm := 1450;
END_DATA_BLOCK
"""


def test_a_global_db_carries_every_variable_where_s7_lays_it_out() -> None:
    program = build(DB)
    block = program.block("DB20")
    layout = block.layout
    assert layout is not None and layout.size == block.size
    slots = layout.slots
    assert slots["warm"] == Slot(0, 0, "BOOL", 0)
    assert slots["ready"] == Slot(0, 1, "BOOL", 0)
    assert slots["avg"] == Slot(2, 0, "REAL", 4)
    assert slots["count"] == Slot(6, 0, "INT", 2)
    assert slots["flags"].type == "ARRAY[0..9] OF BOOL"
    assert slots["grid"].type == "ARRAY[1..2, 1..3] OF INT"
    assert slots["motor[2].speed"].type == "INT" and slots["motor[3]"].type == "STRUCT"
    assert slots["recipe.name"].type == "STRING[6]"
    assert slots["pump.rpm"].type == "INT"


def test_the_member_after_a_string_starts_on_an_even_byte() -> None:
    """A STRING[3] takes 5 bytes; the BYTE after it starts at 6, as after an ARRAY or a
    STRUCT (Program Design for S7-300/400, appendix C)."""
    block = build(
        "DATA_BLOCK DB20 STRUCT s : STRING[3]; b : BYTE; w : INT; END_STRUCT\n"
        "BEGIN s := 'xyz'; b := 16#22; END_DATA_BLOCK\n"
    ).block("DB20")
    assert block.layout is not None
    slots = block.layout.slots
    assert (slots["s"].byte, slots["b"].byte, slots["w"].byte, block.size) == (0, 6, 8, 10)
    assert block.init is not None and block.init[6] == 0x22


def test_the_layout_places_each_variable_where_the_compiler_reads_it() -> None:
    program = build(DB)
    t = program.types["DB20"]
    slots = program.block("DB20").layout.slots
    for name in ("warm", "ready", "avg", "mask", "wait", "motor[3].speed", "recipe.name"):
        parsed = parse_name(f"DB20.{name}")
        assert parsed is not None
        found = member(t, parsed[1], {}, name)
        assert (slots[name].byte, slots[name].bit) == (found.byte, found.bit), name


def test_a_loaded_db_reads_by_name_with_its_type_and_begin_values() -> None:
    cpu, _ = cpu_with(build(DB))
    db = cpu.mem.dbs[20]
    assert db.layout is not None

    def value(name: str) -> object:
        slot = db.layout.slots[name]
        return decode(slot.type, db.data[slot.byte :])

    assert value("avg") == 2.5
    assert value("count") == -7  # INT signed
    assert value("mask") == 0xF00F  # WORD unsigned
    assert value("wait") == 1500  # TIME in ms
    assert value("motor[3].speed") == 9
    assert cpu.mem.dbs[5].layout.slots["rpm"] == Slot(2, 0, "INT", 2)
    assert decode("INT", cpu.mem.dbs[5].data[2:]) == 1450


COUNTER = """
DATA_BLOCK DB20
STRUCT count : INT; END_STRUCT
BEGIN count := 100;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
VAR_TEMP info : ARRAY[0..19] OF BYTE; END_VAR
BEGIN
  DB20.count := DB20.count + 1;
END_ORGANIZATION_BLOCK
"""


def test_a_warm_restart_keeps_a_global_db_and_a_cold_restart_resets_it() -> None:
    cpu, _ = cpu_with(build(COUNTER))
    slot = cpu.mem.dbs[20].layout.slots["count"]

    def count() -> object:
        return decode(slot.type, cpu.mem.dbs[20].data[slot.byte :])

    cpu.start()
    cpu.scan()
    cpu.scan()
    assert count() == 102
    cpu.stop()
    cpu.start("warm")  # S7-300 DBs are retentive: a warm restart keeps them
    assert count() == 102
    cpu.stop()
    cpu.start("cold")  # back to the BEGIN values, the layout kept
    assert count() == 100 and cpu.mem.dbs[20].layout is not None
