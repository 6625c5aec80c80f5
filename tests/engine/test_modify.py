"""Modifying (engine/modify.py, Cpu.modify) on the virtual clock: a value written once at a
scan boundary, where each area's value goes, what the program and the modules see, and the
refusals — and, for random modifies between the scans of a running program, the same state
as the same values written into a second CPU's memory through ``Memory.set``."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from s7graph.engine import CallContext, Cpu, VirtualClock, ob
from s7graph.engine.address import Area
from s7graph.engine.modify import MODIFY_POINTS, ModifyError
from s7graph.engine.symbols import SymbolTable
from tests.engine.test_force import scan


class Program:
    """OB1 records what it reads of I0.3, MW10 and DB20.DBW2; writes Q4.0 := I0.0 and
    increments MW12 every cycle (Q5.0 and M14 it never writes)."""

    def __init__(self) -> None:
        self.seen: list[tuple[bool, int, int]] = []

        @ob(1)
        def main(ctx: CallContext) -> None:
            m = ctx.mem
            self.seen.append((bool(m.get("I0.3")), int(m.get("MW10")), int(m.get("DB20.DBW2"))))  # type: ignore[call-overload]
            m.set("Q4.0", m.get("I0.0"))
            m.set("MW12", (int(m.get("MW12")) + 1) & 0xFFFF)  # type: ignore[call-overload]

        self.ob1 = main


def running(clock: VirtualClock) -> tuple[Cpu, Program]:
    program = Program()
    cpu = Cpu(clock)
    cpu.mem.create_db(20, 8)
    cpu.load(program.ob1)
    cpu.start()
    return cpu, program


def test_a_modified_flag_and_db_word_are_read_by_the_next_scan_and_stay_until_written() -> None:
    clock = VirtualClock()
    cpu, program = running(clock)
    scan(cpu, clock)
    cpu.modify("MW10", -5)
    cpu.modify("DB20.DBW2", "W#16#00FF")
    scan(cpu, clock, 2)
    assert program.seen[-2:] == [(False, 0xFFFB, 0x00FF)] * 2  # written once, not undone
    before = int(cpu.mem.get("MW12"))  # type: ignore[call-overload]
    cpu.modify("MW12", 100)  # the program writes it again at once
    scan(cpu, clock)
    assert cpu.mem.get("MW12") == 101 and before != 100


def test_a_modified_input_is_what_the_next_scan_reads_until_the_modules_deliver_another() -> None:
    clock = VirtualClock()
    cpu, program = running(clock)
    scan(cpu, clock)
    cpu.modify("I0.3", True)
    assert cpu.mem.periph_in[0] == 0b1000 and not cpu.mem.get("I0.3")  # the module side
    scan(cpu, clock)
    assert program.seen[-1][0] is True
    cpu.mem.periph_in[0] = 0  # the modules (the plant) deliver another value
    scan(cpu, clock)
    assert program.seen[-1][0] is False


def test_a_modified_output_reaches_the_modules_unless_the_program_writes_it() -> None:
    clock = VirtualClock()
    cpu, _ = running(clock)
    scan(cpu, clock)
    cpu.modify("Q5.0", True)  # the program never writes it
    cpu.modify("Q4.0", True)  # the program writes Q4.0 := I0.0 (FALSE)
    assert cpu.mem.periph_out[5] == 0  # not before the end of the next scan
    scan(cpu, clock)
    assert cpu.mem.periph_out[5] & 1 and not cpu.mem.periph_out[4] & 1


def test_a_symbol_is_modified_in_its_type_and_a_literal_as_written() -> None:
    clock = VirtualClock()
    cpu, _ = running(clock)
    symbols = SymbolTable()
    symbols.add("Level", "MD16", "REAL")
    symbols.add("Delay", "MD20", "TIME")
    cpu.mem.symbols = symbols
    shown = [str(cpu.modify("Level", 1.5)), str(cpu.modify('"Delay"', "T#5S"))]
    assert shown == ['"Level" (MD16) = 1.5', '"Delay" (MD20) = T#5S']
    assert cpu.mem.get("Level") == 1.5 and cpu.mem.get("Delay") == 5000


def test_what_cannot_be_modified_is_refused_with_the_reason_and_nothing_written() -> None:
    clock = VirtualClock()
    cpu, _ = running(clock)
    cpu.force("M14.0", True)
    scan(cpu, clock)
    image = (bytes(cpu.mem.markers), bytes(cpu.mem.periph_in), bytes(cpu.mem.dbs[20].data))
    refusals = {
        "T3": "cannot be modified: only I, Q, M, DB can",
        "PIW256": "cannot be modified",
        '"Nothing"': "not an S7 address or a symbol",
        "MW8191": "is outside the M area",
        "DB20.DBD6": "is outside DB20 (8 bytes)",
        "DB99.DBW0": "DB99 does not exist",
        "M14.0": "is forced (M14.0 = TRUE): the force value would be written over it",
        "MB14": "unforce M14.0 first",
    }
    for target, reason in refusals.items():
        try:
            cpu.modify(target, 1)
        except ModifyError as exc:
            assert reason in exc.message, (target, exc.message)
        else:
            raise AssertionError(f"{target} was modified")
    for target, value, reason in (
        ("M0.0", 2, "does not fit the bit M0.0: modify TRUE or FALSE"),
        ("MB0", 300, "does not fit the byte MB0"),
        ("MW0", "T#5S", "not a value for the word MW0"),
        ("MW0", None, "no value to modify MW0 to"),
    ):
        try:
            cpu.modify(target, value)
        except ModifyError as exc:
            assert reason in exc.message, (target, exc.message)
        else:
            raise AssertionError(f"{target} := {value!r} was modified")
    assert image == (bytes(cpu.mem.markers), bytes(cpu.mem.periph_in), bytes(cpu.mem.dbs[20].data))
    assert set(MODIFY_POINTS) == {Area.I, Area.Q, Area.M, Area.DB}


BIT, BYTE = st.booleans(), st.integers(0, 255)
WORD, DWORD = st.integers(-32768, 65535), st.integers(-(2**31), 2**32 - 1)
OPERANDS = {
    "I0.3": BIT,
    "IW2": WORD,
    "Q5.0": BIT,
    "QB6": BYTE,
    "M10.1": BIT,
    "MW10": WORD,
    "MD16": DWORD,
    "DB20.DBX0.1": BIT,
    "DB20.DBW2": WORD,
}
MODIFIES = st.lists(
    st.tuples(st.integers(0, 5), st.sampled_from(sorted(OPERANDS))).flatmap(
        lambda t: st.tuples(st.just(t[0]), st.just(t[1]), OPERANDS[t[1]])
    ),
    max_size=12,
)


def _set(cpu: Cpu, operand: str, value: object) -> None:
    """The reference: the value written through ``Memory.set`` (an input on the module
    side, as the modules deliver it)."""
    if operand.startswith("I"):
        shadow = Cpu(VirtualClock())
        shadow.mem.inputs[:] = cpu.mem.periph_in[: len(cpu.mem.inputs)]
        shadow.mem.set(operand, value)
        cpu.mem.periph_in[: len(cpu.mem.inputs)] = shadow.mem.inputs
        return
    cpu.mem.set(operand, value)


@settings(max_examples=60, deadline=None)
@given(MODIFIES)
def test_random_modifies_of_a_running_program_equal_the_same_writes_into_a_fresh_cpu(
    modifies: list[tuple[int, str, object]],
) -> None:
    clocks = VirtualClock(), VirtualClock()
    (cpu, program), (fresh, reference) = running(clocks[0]), running(clocks[1])
    for n in range(6):
        for at, operand, value in modifies:
            if at == n:
                cpu.modify(operand, value)
                _set(fresh, operand, value)
        scan(cpu, clocks[0])
        scan(fresh, clocks[1])
        assert program.seen == reference.seen
    for area in ("inputs", "outputs", "markers", "periph_in", "periph_out"):
        assert getattr(cpu.mem, area) == getattr(fresh.mem, area), area
    assert cpu.mem.dbs[20].data == fresh.mem.dbs[20].data


def test_an_address_given_with_its_type_and_variable_is_modified_as_that_type() -> None:
    from s7graph.engine.address import parse_address

    clock = VirtualClock()
    cpu, _ = running(clock)
    done = cpu.modify(parse_address("DB20.DBW2"), "-5", type_name="INT", variable="DB20.count")
    assert str(done) == "DB20.count (DB20.DBW2) = -5"
    assert cpu.mem.get("DB20.DBW2") == 0xFFFB
    with pytest.raises(ModifyError, match=r"DB20\.count"):
        cpu.modify(parse_address("DB20.DBW2"), "T#5S", type_name="INT", variable="DB20.count")
    assert cpu.mem.get("DB20.DBW2") == 0xFFFB


def test_a_value_for_a_variable_follows_the_rules_of_a_modify_of_its_type() -> None:
    from s7graph.engine.modify import typed_value

    assert typed_value("INT", "v", "-5") == (-5, "-5")
    assert typed_value("TIME", "v", "T#5S") == (5000, "T#5S")
    assert typed_value("REAL", "v", 2) == (2.0, "2.0")
    assert typed_value("BOOL", "v", 1) == (True, "TRUE")
    assert typed_value("WORD", "v", "16#00FF") == (255, "W#16#00FF")
    assert typed_value("CHAR", "v", "'a'") == ("a", "CHAR#97")  # one character: a CHAR
    for type_name, value, says in (
        ("INT", True, "takes a number"),
        ("INT", 70000, "out of range"),
        ("BOOL", 2, "TRUE or FALSE"),
        ("STRING[8]", "'x'", "a bit, a byte, a word or a double word"),
        ("CHAR", "'ab'", "is a STRING"),
        ("LREAL", 1.5, "a bit, a byte, a word or a double word"),
    ):
        with pytest.raises(ModifyError) as refused:
            typed_value(type_name, "DB10.v", value)
        assert says in refused.value.message and "DB10.v" in refused.value.message
