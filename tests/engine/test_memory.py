"""Operand memory (docs/runtime.md, "The block runtime" and "Restarts: warm, hot, cold"; Siemens'
Program Design for S7-300/400, ch. 5 and 9)."""

from __future__ import annotations

import json
from datetime import datetime

import pytest

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.datatypes import layout
from s7graph.engine.errors import AddressError, BlockError, TypeMismatch
from s7graph.engine.memory import AreaLengthError, Memory, S5Counter, S5Timer


def A(text: str) -> Address:
    return parse_address(text)


@pytest.fixture
def mem() -> Memory:
    return Memory()


def test_word_is_big_endian_with_high_byte_at_the_lower_address(mem: Memory) -> None:
    """L W#16#1234; T MW10 → MB10 = 16#12, MB11 = 16#34."""
    mem.write(A("MW10"), 0x1234)
    assert (mem.read(A("MB10")), mem.read(A("MB11"))) == (0x12, 0x34)


def test_bit_0_of_the_first_byte_is_bit_8_of_the_word(mem: Memory) -> None:
    """M10.0 is bit 0 of MB10 = bit 8 of MW10."""
    mem.write(A("M10.0"), True)
    assert mem.read(A("MW10")) == 0x0100
    assert mem.read(A("MB10")) == 0x01


def test_dword_spans_four_bytes_most_significant_first(mem: Memory) -> None:
    """Siemens' Program Design for S7-300/400, ch. 5: MD100 = MB100..MB103."""
    mem.write(A("MD100"), 0x01020304)
    assert [mem.read(A(f"MB{n}")) for n in range(100, 104)] == [1, 2, 3, 4]
    assert mem.read(A("MW101")) == 0x0203


def test_typed_access_converts_s7_types(mem: Memory) -> None:
    mem.write_as(A("MW0"), "INT", -1)
    mem.write_as(A("MD2"), "REAL", 1.5)
    mem.write_as(A("MD6"), "TIME", -1000)
    mem.write_as(A("MW10"), "S5TIME", 2000)
    assert mem.read(A("MW0")) == 0xFFFF
    assert mem.read_as(A("MW0"), "INT") == -1
    assert mem.read_as(A("MD2"), "REAL") == 1.5
    assert mem.read_as(A("MD6"), "TIME") == -1000
    assert mem.read(A("MW10")) == 0x0200


def test_long_types_are_read_from_the_first_byte(mem: Memory) -> None:
    """STRING[n] and DT live at a start byte and span n+2 / 8 bytes."""
    db = mem.create_db(5, 20)
    mem.write_as(A("DB5.DBB0"), "STRING[6]", "+205")
    mem.write_as(A("DB5.DBB8"), "DT", datetime(2026, 11, 22, 8, 30, 1, 999_000))
    assert db.data[:2] == bytes([6, 4])
    assert mem.read_as(A("DB5.DBB0"), "STRING[6]") == "+205"
    assert mem.read_as(A("DB5.DBB8"), "DT") == datetime(2026, 11, 22, 8, 30, 1, 999_000)


def test_type_that_does_not_match_the_address_width_is_a_type_mismatch(mem: Memory) -> None:
    with pytest.raises(TypeMismatch, match="MB0"):
        mem.read_as(A("MB0"), "INT")
    with pytest.raises(TypeMismatch):
        mem.write_as(A("M0.0"), "STRING[4]", "ab")


@pytest.mark.parametrize(
    ("text", "value"), [("MB0", 256), ("MW0", -1), ("MW0", 0x10000), ("M0.0", 2), ("MD0", 1.5)]
)
def test_raw_write_out_of_range_for_the_width_is_a_type_mismatch(
    mem: Memory, text: str, value: int
) -> None:
    with pytest.raises(TypeMismatch):
        mem.write(A(text), value)


def test_typed_write_out_of_range_is_a_type_mismatch(mem: Memory) -> None:
    with pytest.raises(TypeMismatch):
        mem.write_as(A("MW0"), "INT", 40000)
    assert mem.read(A("MW0")) == 0


def test_reading_beyond_a_db_is_an_area_length_error(mem: Memory) -> None:
    """DB access beyond its length is an area-length error (SW_FLT 16#22/23)."""
    mem.create_db(1, 10)
    assert mem.read(A("DB1.DBW8")) == 0
    with pytest.raises(AreaLengthError, match=r"DB1\.DBD8") as read_err:
        mem.read(A("DB1.DBD8"))
    with pytest.raises(AreaLengthError) as write_err:
        mem.write(A("DB1.DBX10.0"), True)
    assert (read_err.value.sw_flt, write_err.value.sw_flt) == (0x22, 0x23)


def test_area_length_error_is_an_address_error(mem: Memory) -> None:
    """Callers catching AddressError also see area-length errors."""
    with pytest.raises(AddressError, match="MW255"):
        mem.read(A("MW255"))


def test_missing_db_raises_address_error_naming_the_address(mem: Memory) -> None:
    with pytest.raises(AddressError, match=r"DB7\.DBW0"):
        mem.read(A("DB7.DBW0"))


def test_timer_or_counter_number_beyond_the_cells_is_an_address_error() -> None:
    mem = Memory(timers=4, counters=4)
    with pytest.raises(AddressError, match="T4"):
        mem.read(A("T4"))
    with pytest.raises(AddressError, match="C9"):
        mem.read(A("C9"))


def test_timer_reads_status_as_bool_and_binary_value_as_word(mem: Memory) -> None:
    """El-Shahat's S7-300/400 course, timers and counters: ``A T n`` status bit, ``L T n`` binary
    without time base."""
    mem.timers[5] = S5Timer(value_ms=1230, time_base_ms=10, q=True)
    assert mem.read_as(A("T5"), "BOOL") is True
    assert mem.read(A("T5")) == 123
    assert mem.read_as(A("T5"), "S5TIME") == 1230
    assert mem.timers[5].bcd() == 0x0123
    with pytest.raises(TypeMismatch):
        mem.write(A("T5"), 3)


def test_counter_value_saturates_and_q_means_nonzero() -> None:
    """El-Shahat's S7-300/400 course, timers and counters: 0..999, Q = value > 0."""
    cell = S5Counter()
    cell.set_value(1200)
    assert (cell.value, cell.q, cell.bcd()) == (999, True, 0x999)
    cell.set_value(-3)
    assert (cell.value, cell.q) == (0, False)


def test_peripheral_access_goes_to_the_module_side_not_the_process_image(mem: Memory) -> None:
    """docs/runtime.md, "The block runtime": PI/PQ are the module side; I is only the process
    image."""
    mem.periph_in[0:2] = b"\x12\x34"
    assert mem.read(A("PIW0")) == 0x1234
    assert mem.read(A("IW0")) == 0
    mem.write(A("PQB200"), 7)
    assert mem.periph_out[200] == 7


def test_peripheral_output_inside_the_q_image_updates_q_too(mem: Memory) -> None:
    """Siemens' Program Design for S7-300/400, ch. 5 [K]: PQx within the PIQ range also updates the
    PIQ."""
    mem.write(A("PQW0"), 0xBEEF)
    assert mem.read(A("QW0")) == 0xBEEF
    quiet = Memory(pq_updates_q=False)
    quiet.write(A("PQW0"), 0xBEEF)
    assert quiet.read(A("QW0")) == 0


def test_fast_paths_share_the_live_bytes(mem: Memory) -> None:
    mem.write_bit(Area.Q, 4, 1, True)
    assert mem.read(A("Q4.1")) is True
    assert mem.read_bit("Q", 4, 1) is True
    mem.area_bytes(Area.I)[0] = 0x80
    assert mem.read(A("I0.7")) is True
    db = mem.create_db(2, 4)
    assert mem.area_bytes(Area.DB, 2) is db.data


def test_fast_bit_access_outside_the_area_is_an_area_length_error(mem: Memory) -> None:
    with pytest.raises(AreaLengthError):
        mem.read_bit(Area.I, 128, 0)


def test_get_and_set_take_address_text(mem: Memory) -> None:
    mem.set("MW2", -5)
    mem.set("MD4", 2.5)
    mem.set("Q 0.1", True)
    assert mem.get("MW2") == 0xFFFB
    assert mem.read_as(A("MW2"), "INT") == -5
    assert mem.read_as(A("MD4"), "REAL") == 2.5
    assert mem.get("A0.1") is True


def test_create_db_pads_init_and_refuses_duplicates(mem: Memory) -> None:
    db = mem.create_db(3, 4, init=b"\x01")
    assert bytes(db.data) == b"\x01\0\0\0"
    with pytest.raises(BlockError):
        mem.create_db(3, 4)
    with pytest.raises(BlockError):
        mem.create_db(4, 1, init=b"\1\2")


def test_db_field_address_uses_the_layout(mem: Memory) -> None:
    db = mem.create_db(9, 4, layout=layout([("on", "BOOL"), ("speed", "INT")]))
    mem.write_as(db.field_address("speed"), "INT", -7)
    assert mem.get("DB9.DBW2") == 0xFFF9
    assert str(db.field_address("on")) == "DB9.DBX0.0"


def test_warm_restart_clears_non_retentive_markers_timers_counters_and_keeps_dbs(
    mem: Memory,
) -> None:
    """Non-retentive M/T/C zeroed, retentive M (MB0..15) and C (C0..7) and DBs kept."""
    mem.write(A("MB15"), 1)
    mem.write(A("MB16"), 2)
    mem.counters[7].set_value(5)
    mem.counters[8].set_value(5)
    mem.timers[0].q = True
    db = mem.create_db(1, 2)
    db.data[0] = 9
    mem.clear_non_retentive()
    assert (mem.read(A("MB15")), mem.read(A("MB16"))) == (1, 0)
    assert (mem.counters[7].value, mem.counters[8].value) == (5, 0)
    assert mem.timers[0].q is False
    assert db.data[0] == 9


def test_cold_restart_resets_everything_and_reloads_db_initial_values(mem: Memory) -> None:
    """All M/T/C zeroed incl. retentive; runtime DBs deleted; DBs re-initialised."""
    mem.write(A("MB0"), 1)
    mem.counters[0].set_value(3)
    db = mem.create_db(1, 2, init=b"\x05\x06")
    db.data[:] = b"\0\0"
    mem.create_db(2, 2, created=True)
    mem.reset_to_initial()
    assert mem.read(A("MB0")) == 0
    assert mem.counters[0].value == 0
    assert bytes(db.data) == b"\x05\x06"
    assert 2 not in mem.dbs


def test_snapshot_is_json_and_restores_only_retentive_parts(mem: Memory) -> None:
    mem.write(A("MB1"), 0x11)
    mem.write(A("MB20"), 0x22)
    mem.counters[2].set_value(42)
    mem.create_db(1, 4, init=b"\1").data[3] = 7
    mem.create_db(2, 4, retain=False).data[0] = 1
    saved = json.loads(json.dumps(mem.snapshot()))
    fresh = Memory()
    fresh.restore(saved)
    assert (fresh.read(A("MB1")), fresh.read(A("MB20"))) == (0x11, 0)
    assert (fresh.counters[2].value, fresh.counters[2].q) == (42, True)
    assert bytes(fresh.dbs[1].data) == b"\1\0\0\7"
    assert bytes(fresh.dbs[1].initial) == b"\1\0\0\0"
    assert 2 not in fresh.dbs


def test_retentive_ranges_are_configurable() -> None:
    mem = Memory(retentive_markers=range(0), retentive_timers=range(0, 2))
    mem.write(A("MB0"), 1)
    mem.timers[1] = S5Timer(value_ms=500, running=True)
    mem.clear_non_retentive()
    assert mem.read(A("MB0")) == 0
    assert mem.timers[1].running is True
    saved = mem.snapshot()
    other = Memory(retentive_timers=range(0, 2))
    other.restore(saved)
    assert (other.timers[1].value_ms, other.timers[1].running) == (500, True)
