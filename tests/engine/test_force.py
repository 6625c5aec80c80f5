"""Forcing (engine/force.py, Cpu.force/unforce) on the virtual clock: where in the scan each
area's force values are written, what the program and the modules see, the diagnostic
entries, the refusals, and the force table through the state file."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, VirtualClock, ob
from s7graph.engine.address import Area, parse_address
from s7graph.engine.force import FORCE_POINTS, MAX_FORCES, ForceError, ForcePoint
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.symbols import SymbolTable


class Program:
    """OB1 records what it reads of I0.3, IW2 and M10.1, and writes Q4.0 := I0.0 and
    QW6 := 1234 and M10.1 := FALSE every cycle."""

    def __init__(self) -> None:
        self.seen: list[tuple[bool, int, bool]] = []

        @ob(1)
        def main(ctx: CallContext) -> None:
            m = ctx.mem
            self.seen.append((bool(m.get("I0.3")), int(m.get("IW2")), bool(m.get("M10.1"))))  # type: ignore[call-overload]
            m.set("Q4.0", m.get("I0.0"))
            m.set("QW6", 1234)
            m.set("M10.1", False)

        self.ob1 = main


def running(clock: VirtualClock) -> tuple[Cpu, Program]:
    program = Program()
    cpu = Cpu(clock)
    cpu.load(program.ob1)
    cpu.start()
    return cpu, program


def scan(cpu: Cpu, clock: VirtualClock, n: int = 1) -> None:
    for _ in range(n):
        clock.advance(10)
        cpu.scan()


def test_a_forced_input_is_what_ob1_reads_whatever_the_module_says(clock: VirtualClock) -> None:
    cpu, program = running(clock)
    cpu.mem.periph_in[0] = 0  # I0.3 is 0 on the module
    cpu.mem.periph_in[2:4] = (7).to_bytes(2, "big")
    cpu.force("I0.3", True)
    cpu.force("IW2", -5)
    scan(cpu, clock, 2)
    assert program.seen[-2:] == [(True, 0xFFFB, False)] * 2
    assert cpu.mem.periph_in[0] == 0  # the module side is untouched
    cpu.mem.periph_in[0] = 0xFF  # the module changes: bit 3 stays forced, the others follow
    cpu.force("I0.3", False)
    scan(cpu, clock)
    assert program.seen[-1][0] is False and cpu.mem.inputs[0] == 0xF7


def test_a_forced_output_reaches_the_modules_whatever_the_program_writes(
    clock: VirtualClock,
) -> None:
    cpu, _ = running(clock)
    cpu.mem.periph_in[0] = 1  # I0.0: the program writes Q4.0 := 1
    cpu.force("Q4.0", False)
    cpu.force("QW6", 0x00FF)
    scan(cpu, clock)
    mem = cpu.mem
    assert mem.periph_out[4] & 1 == 0
    assert int.from_bytes(mem.periph_out[6:8], "big") == 0x00FF
    assert mem.get("Q4.0") is False  # the output image holds the force value after the cycle
    clock.advance(10)
    record = cpu.scan()
    assert "PQB4" not in record.outputs  # and keeps it: no change reaches the modules


def test_unforce_gives_control_back_to_the_program_and_the_modules(clock: VirtualClock) -> None:
    cpu, program = running(clock)
    cpu.mem.periph_in[0] = 1
    cpu.force("I0.3", True)
    cpu.force("Q4.0", False)
    scan(cpu, clock)
    assert program.seen[-1][0] and not cpu.mem.periph_out[4] & 1
    gone = cpu.unforce("I0.3")
    assert [str(f.address) for f in gone] == ["I0.3"]
    scan(cpu, clock)
    assert program.seen[-1][0] is False and not cpu.mem.periph_out[4] & 1  # Q4.0 still forced
    assert [str(f.address) for f in cpu.unforce()] == ["Q4.0"]
    scan(cpu, clock)
    assert cpu.mem.periph_out[4] & 1 and len(cpu.forces) == 0


def test_a_forced_flag_is_written_at_the_start_of_the_cycle_and_the_program_may_overwrite_it(
    clock: VirtualClock,
) -> None:
    """S7-400 forces M (an S7-300 cannot): the force value before OB1, every cycle; OB1's
    own write of M10.1 stands until the next cycle starts."""
    assert FORCE_POINTS[Area.M] is ForcePoint.CYCLE_START
    cpu, program = running(clock)
    cpu.force("M10.1", True)
    scan(cpu, clock, 3)
    assert [seen[2] for seen in program.seen[-3:]] == [True, True, True]
    assert cpu.mem.get("M10.1") is False  # OB1 wrote FALSE after reading the force value


def test_forcing_starts_and_ends_with_a_diagnostic_entry_in_the_scan_it_acts_in(
    clock: VirtualClock,
) -> None:
    cpu, _ = running(clock)
    cpu.force("I0.3", True, user="eng")
    assert not [e for e in cpu.diagnostics if e.event_id == EventId.FORCE_STARTED]
    clock.advance(10)
    record = cpu.scan()
    (entry,) = [e for e in record.diagnostics if e.event_id == EventId.FORCE_STARTED]
    assert entry.address == "I0.3" and entry.t_ns == record.t_ns
    assert entry.message == "force I0.3 = TRUE by eng; 1 force job active"
    cpu.force("I0.3", False, user="eng")
    cpu.force("MW10", 300)
    clock.advance(10)
    texts = [e.message for e in cpu.scan().diagnostics]
    assert texts == [
        "force I0.3 = FALSE (was TRUE) by eng; 1 force job active",
        "force MW10 = 300; 2 force jobs active",
    ]
    cpu.unforce("MW10", user="eng")
    cpu.unforce(user="eng")
    clock.advance(10)
    ended = [(e.event_id, e.message) for e in cpu.scan().diagnostics]
    assert ended == [
        (EventId.FORCE_ENDED, "unforce MW10 (was 300) by eng; 1 force job active"),
        (EventId.FORCE_ENDED, "unforce all by eng: 1 force job deleted (I0.3)"),
    ]


def test_symbols_and_typed_values_are_forced_in_the_symbols_type(clock: VirtualClock) -> None:
    cpu, _ = running(clock)
    symbols = SymbolTable()
    symbols.add("Start_button", "I0.0")
    symbols.add("Speed", "MW20", "INT")
    symbols.add("Delay", "MD24", "TIME")
    symbols.add("Level", "MD28", "REAL")
    cpu.mem.symbols = symbols
    forces = [
        cpu.force('"Start_button"', True),
        cpu.force("Speed", "-5"),
        cpu.force("Delay", "T#5S"),
        cpu.force("Level", 1.5),
        cpu.force("QB8", "B#16#A5"),
        cpu.force("QD12", 2.5),
    ]
    assert [str(f) for f in forces] == [
        '"Start_button" (I0.0) = TRUE',
        '"Speed" (MW20) = -5',
        '"Delay" (MD24) = T#5S',
        '"Level" (MD28) = 1.5',
        "QB8 = B#16#A5",
        "QD12 = 2.5",
    ]
    scan(cpu, clock)
    assert cpu.mem.get("Speed") == -5 and cpu.mem.get("Delay") == 5000
    assert cpu.mem.get("Level") == 1.5 and cpu.mem.periph_out[8] == 0xA5
    assert cpu.mem.read_as(parse_address("QD12"), "REAL") == 2.5


@pytest.mark.parametrize(
    ("target", "value", "problem"),
    [
        ("I0.9", True, "bit 9 outside 0..7"),
        ("Nonsense", True, "not an S7 address or a symbol"),
        ('"Missing"', True, 'unknown symbol "Missing"'),
        ("DB1.DBX0.0", True, "DB1.DBX0.0 cannot be forced: only I, Q, M can"),
        ("T5", 1, "T5 cannot be forced"),
        ("PIW256", 1, "PIW256 cannot be forced"),
        ("IB200", 1, "IB200 is outside the I area (128 bytes)"),
        ("I0.3", 2, "2 does not fit the bit I0.3: force TRUE or FALSE"),
        ("I0.3", "B#16#1", "B#16#01 is a BYTE (8 bits), not a value for the bit I0.3"),
        ("MB4", 256, "256 does not fit the byte MB4 (0..255, or -128..127)"),
        ("MW4", -40000, "-40000 does not fit the word MW4"),
        ("MW4", True, "the word MW4 takes a number, not TRUE"),
        ("MW4", 1.5, "1.5 is a REAL (32 bits), not a value for the word MW4"),
        ("MW4", "T#5S", "T#5S is a TIME (32 bits), not a value for the word MW4"),
        ("MW4", "hello", "bad literal 'hello': not a literal (to force the word MW4)"),
        ("Q0.0", None, "no value to force Q0.0 to"),
        ("I" * 70, True, "not an address or symbol"),
    ],
)
def test_bad_force_jobs_are_refused_naming_the_problem(
    clock: VirtualClock, target: str, value: object, problem: str
) -> None:
    cpu, _ = running(clock)
    with pytest.raises(ForceError) as caught:
        cpu.force(target, value)
    assert problem in str(caught.value)
    assert str(caught.value).count("not an S7 address") <= 1  # once, never "…: not an S7 …"
    assert len(cpu.forces) == 0


def test_overlapping_jobs_and_a_full_table_are_refused(clock: VirtualClock) -> None:
    cpu, _ = running(clock)
    cpu.force("MW10", 1)
    with pytest.raises(ForceError, match=r"M10\.1 overlaps the force job MW10 = 1: unforce MW10"):
        cpu.force("M10.1", True)
    cpu.force("M12.0", True)
    cpu.force("M12.1", True)  # another bit of the same byte is no overlap
    with pytest.raises(ForceError, match=r"I0\.0 is not forced"):
        cpu.unforce("I0.0")
    cpu.unforce()
    for i in range(MAX_FORCES):
        cpu.force(f"M{i // 8}.{i % 8}", True)
    with pytest.raises(ForceError, match=f"the force table is full \\({MAX_FORCES} jobs\\)"):
        cpu.force("Q0.0", True)


def test_outputs_stay_0_outside_run_forced_or_not(clock: VirtualClock) -> None:
    cpu, _ = running(clock)
    cpu.force("Q4.0", True)
    scan(cpu, clock)
    assert cpu.mem.periph_out[4] & 1
    cpu.stop()
    scan(cpu, clock)
    assert cpu.mem.periph_out[4] == 0 and cpu.mode is CpuMode.STOP
    assert len(cpu.forces) == 1  # the job stays until deleted
    cpu.start("cold")
    scan(cpu, clock)
    assert cpu.mem.periph_out[4] & 1  # and acts again in RUN, after any restart


def test_a_memory_reset_deletes_the_force_jobs(clock: VirtualClock) -> None:
    cpu, _ = running(clock)
    cpu.force("I0.3", True)
    cpu.stop()
    cpu.memory_reset()
    assert len(cpu.forces) == 0
    assert cpu.diagnostics.latest()[0].message == "memory reset deletes 1 force job: I0.3"


def test_forces_survive_a_save_and_load_and_act_after_the_restart(
    clock: VirtualClock, tmp_path: Path
) -> None:
    cpu, _ = running(clock)
    cpu.force("I0.3", True, user="eng")
    cpu.force("QW6", 77)
    scan(cpu, clock)
    store = StateStore(tmp_path / "s.sqlite")
    store.save(cpu)
    store.close()

    fresh, cpu2 = Program(), Cpu(clock)
    cpu2.load(fresh.ob1)
    store = StateStore(tmp_path / "s.sqlite")
    store.load(cpu2)
    assert [(str(f), f.user) for f in cpu2.forces] == [("I0.3 = TRUE", "eng"), ("QW6 = 77", "")]
    cpu2.start("warm")
    scan(cpu2, clock)
    assert fresh.seen[-1][0] is True and int.from_bytes(cpu2.mem.periph_out[6:8], "big") == 77
    cpu2.unforce()
    batch = store.stage(cpu2)
    assert batch is not None and batch.meta["forces"] == "[]"  # the deletion is written too
    store.close()


def test_a_malformed_force_table_in_the_state_file_is_refused(
    clock: VirtualClock, tmp_path: Path
) -> None:
    cpu, _ = running(clock)
    store = StateStore(tmp_path / "s.sqlite")
    store.save(cpu)
    with sqlite3.connect(tmp_path / "s.sqlite") as db:
        db.execute(
            "UPDATE meta SET value=? WHERE key='forces'",
            ('[{"address": "DB1.DBX0.0", "value": 1}]',),
        )
    store.close()
    with pytest.raises(StateFileError, match=r"malformed force table: .*cannot be forced"):
        StateStore(tmp_path / "s.sqlite").load(Cpu(clock))
