"""A user FB's instance DB read by name in a chart (``"Motor_DB".Running``, ``DB12.calls``):
when the program's blocks are known at compile time (``--blocks``: S7-SCL sources, or a
Python program of blocks), a condition reads an output, in/out or static variable of the
FB whose instance DB a call of the chart names; a name the FB lacks is E048 listing what
it has; without the blocks E048 says so. The chart reads the instance DB the CPU holds at
each scan, also one made again when its FB is downloaded."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from s7graph import sfb
from s7graph.engine import CallContext, Cpu, CpuMode, VirtualClock
from s7graph.engine.blocks import FB, InstanceDB, fb, fc
from s7graph.sequencer.calls import prepare_calls
from s7graph.sequencer.checks.interfaces import ProgramBlocks, program_blocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from s7graph.steps.scl import SclProgram, compile_scl
from s7graph.web.harness.session import ChartSession

SCL = """
FUNCTION_BLOCK FB17
VAR_INPUT start : BOOL; END_VAR
VAR_OUTPUT Running : BOOL; END_VAR
VAR calls : INT; speeds : ARRAY[1..2] OF INT; END_VAR
  calls := calls + 1;
  Running := start AND calls >= 3;
END_FUNCTION_BLOCK
"""


def chart_text(condition: str = '"Motor_DB".Running', call: str = "CALL FB 17, DB 12") -> str:
    return f"""FUNCTION_BLOCK "Line" FB 1 DB 1
SYMBOLS "Motor_DB" : DB12 : FB17; END_SYMBOLS
SEQUENCE 1 "A"
  INITIAL_STEP S1 "wait": END_STEP
  STEP S2 "run": {call} (start := TRUE); END_STEP
  STEP S3 "done": N Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := {condition};
  TRANSITION T3 FROM S3 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def scl_program() -> SclProgram:
    return compile_scl(SCL, "motor.scl", blocks=sfb.SYSTEM_BLOCKS)


def interfaces(blocks: list[Any]) -> ProgramBlocks:
    return program_blocks(blocks, sources="motor.scl")


def run(text: str, blocks: list[Any]) -> tuple[Cpu, VirtualClock, GraphFB]:
    clock = VirtualClock()
    cpu = Cpu(clock)
    sfb.install(cpu)
    cpu.load(*blocks)
    g = GraphFB(compile_chart(parse_chart(text, "line.s7g"), blocks=interfaces(blocks)))
    install_all(cpu, [g])
    assert prepare_calls(cpu, g.cc.chart).created == [12]
    cpu.start("warm")
    cpu.mem.periph_in[0] = 1
    return cpu, clock, g


def scans(cpu: Cpu, clock: VirtualClock, n: int) -> None:
    for _ in range(n):
        cpu.scan()
        clock.advance(100)


def errors(text: str, blocks: ProgramBlocks | None) -> list[tuple[str, int, int, str]]:
    found = validate(parse_chart(text, "line.s7g"), blocks=blocks)
    return [(d.code, d.loc.line, d.loc.col, d.message) for d in found if d.is_error]


def test_a_transition_reads_an_scl_fbs_output_by_its_db_symbol_and_switches_when_it_is_set() -> (
    None
):
    cpu, clock, g = run(chart_text(), scl_program().blocks)
    scans(cpu, clock, 2)  # S2 is entered, and FB17 called, from the first scan on
    assert g.state.active == [1] and cpu.instance_db(12)["Running"] is False
    scans(cpu, clock, 1)  # Running is set by the third call, after T2 was evaluated
    assert g.state.active == [1] and cpu.instance_db(12)["Running"] is True
    scans(cpu, clock, 1)
    assert g.state.active == [2] and cpu.mode is CpuMode.RUN
    assert cpu.mem.get("Q0.0") is True


def test_a_static_variable_is_read_by_the_db_number_in_any_case() -> None:
    cpu, clock, g = run(chart_text("DB12.CALLS >= 5"), scl_program().blocks)
    scans(cpu, clock, 5)
    assert g.state.active == [1] and cpu.instance_db(12)["calls"] == 5
    scans(cpu, clock, 1)
    assert g.state.active == [2]


@fb(17, "Motor", IN={"start": "BOOL"}, OUT={"Running": "BOOL"}, STAT={"calls": "INT"})
def python_motor(ctx: CallContext, db: InstanceDB) -> None:
    db.calls = int(db.calls) + 1  # type: ignore[call-overload]
    db.Running = bool(db.start) and int(db.calls) >= 3  # type: ignore[call-overload]


def test_a_python_fbs_output_is_read_as_an_scl_fbs() -> None:
    cpu, clock, g = run(chart_text(), [python_motor])
    scans(cpu, clock, 3)
    assert g.state.active == [1] and cpu.instance_db(12)["Running"] is True
    scans(cpu, clock, 1)
    assert g.state.active == [2]


@pytest.mark.parametrize(
    ("condition", "why"),
    [
        (
            "DB12.Nope",
            "Nope is not a variable of FB17 (its outputs and static variables: Running, "
            "calls, speeds)",
        ),
        ('"Motor_DB".start', "start is an input of FB17"),
        ("DB12.speeds", "speeds of FB17 is an ARRAY, a STRUCT or a multi-instance"),
    ],
)
def test_a_variable_the_fb_does_not_give_is_e048_naming_it(condition: str, why: str) -> None:
    found = errors(chart_text(condition), interfaces(scl_program().blocks))
    assert [f[:3] for f in found] == [("E048", 8, 34)] and why in found[0][3]


def test_without_the_programs_blocks_a_user_fbs_variable_is_e048_saying_so() -> None:
    (found,) = errors(chart_text(), None)
    assert (
        found[0] == "E048" and "read by name only with the program's blocks (--blocks)" in found[3]
    )


def test_a_call_of_a_block_the_program_lacks_is_e047_and_its_variable_e048() -> None:
    found = errors(chart_text(call="CALL FB 18, DB 12"), interfaces(scl_program().blocks))
    assert [f[0] for f in found] == ["E047", "E048"]
    assert "FB18 is not in the program's blocks (motor.scl)" in found[1][3]


@fc(5, "Twice", IN={"x": "INT"}, OUT={"y": "INT"})
def twice(ctx: CallContext, x: int) -> None:
    return None


def test_an_fc_has_no_instance_db_to_read_by_name() -> None:
    found = errors(chart_text(call="CALL FC 5, DB 12"), interfaces([twice]))
    assert found[-1][0] == "E048" and 'FC5 "Twice" is an FC: it has no instance DB' in found[-1][3]


def test_the_chart_reads_the_instance_db_made_again_by_a_download_of_its_fb() -> None:
    cpu, clock, g = run(chart_text("DB12.calls >= 100"), scl_program().blocks)
    scans(cpu, clock, 2)
    again: FB = next(b for b in scl_program().blocks if isinstance(b, FB))
    cpu.load(again)
    cpu.replace_instance_db(12, again)  # as a download of changed S7-SCL sources does
    cpu.instance_db(12)["calls"] = 98
    scans(cpu, clock, 2)
    assert g.state.active == [1]  # 99 after the call of the first scan: the new DB's
    scans(cpu, clock, 1)
    assert g.state.active == [2] and cpu.mode is CpuMode.RUN


def test_sim_loads_a_chart_reading_a_variable_of_its_blocks(tmp_path: Path) -> None:
    (tmp_path / "line.s7g").write_text(chart_text(), encoding="utf-8")
    (tmp_path / "motor.scl").write_text(SCL, encoding="utf-8")
    (tmp_path / "symbols.txt").write_text('"Motor_DB" ; DB 12 ; FB 17\n', encoding="utf-8")
    session = ChartSession.load(  # the DB symbol in the chart and in --symbols: no clash
        tmp_path / "line.s7g",
        tmp_path / "symbols.txt",
        VirtualClock(),
        blocks=[tmp_path / "motor.scl"],
    )
    session.start()
    session.cpu.mem.periph_in[0] = 1
    for _ in range(5):
        session.scan()
    assert session.graph.state.active == [2] and session.cpu.mode is CpuMode.RUN
