"""S7-SCL blocks called from a chart: a GRAPH FB's CALL rows and permanent instructions
reach FBs and FCs written in SCL through the CPU's block table (docs/scl.md, "Calls";
docs/semantics.md, "Actions")."""

from __future__ import annotations

from s7graph import sfb
from s7graph.engine import Cpu, CpuMode, VirtualClock
from s7graph.sequencer.calls import prepare_calls
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from tests.steps.scl.helpers import build

SCL = """
FUNCTION_BLOCK FB17
VAR_INPUT FINALVAL : INT; END_VAR
VAR_OUTPUT CONTROL : BOOL; END_VAR
VAR INDEX, n : INT; END_VAR
  n := n + 1;
  CONTROL := n >= FINALVAL;
  M1.0 := CONTROL;
END_FUNCTION_BLOCK

FUNCTION FC5 : VOID
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT twice : INT; END_VAR
  twice := 2 * x;
END_FUNCTION
"""

CHART = """
FUNCTION_BLOCK "Seq" FB 1 DB 1
PERMANENT BEFORE
  CALL FC 5 (x := MW10, twice => MW12);
END_PERMANENT
SEQUENCE 1 "S"
  INITIAL_STEP S1 "wait":
  END_STEP
  STEP S2 "count":
    CALL FB 17, DB 10 (FINALVAL := 3);
  END_STEP
  STEP S3 "done":
    N Q0.0;
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := M1.0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_a_chart_calls_an_scl_fb_and_fc() -> None:
    cpu = Cpu(VirtualClock())
    sfb.install(cpu)
    program = build(SCL)
    program.load(cpu)
    cc = compile_chart(parse_chart(CHART, "seq.s7g"))
    install_all(cpu, [GraphFB(cc)])
    plan = prepare_calls(cpu, cc.chart)
    assert plan.missing == [] and plan.created == [10]  # the FB's instance DB, as for an SFB
    cpu.start()
    cpu.mem.set("MW10", 21)
    cpu.scan()
    assert cpu.mem.get("MW12") == 42
    cpu.mem.periph_in[0] = 1
    for _ in range(5):
        cpu.scan()
        cpu.clock.advance(10)  # type: ignore[attr-defined]
    assert cpu.mode is CpuMode.RUN
    assert cpu.instance_db(10)["n"] == 3
    assert cpu.mem.get("Q0.0") is True


def test_a_chart_passes_a_block_db_input_the_dbs_number_as_a_word() -> None:
    """The engine's interface holds a BLOCK_DB as the WORD with the DB's number: a chart's
    CALL gives it ``W#16#5`` (docs/scl.md, "Operands")."""
    scl = """
DATA_BLOCK DB5
STRUCT a : INT := 11; END_STRUCT
BEGIN
END_DATA_BLOCK
FUNCTION FC5 : VOID
VAR_INPUT src : BLOCK_DB; END_VAR
  MW12 := src.DW0;
END_FUNCTION
"""
    chart = CHART.replace("CALL FC 5 (x := MW10, twice => MW12);", "CALL FC 5 (src := W#16#5);")
    cpu = Cpu(VirtualClock())
    sfb.install(cpu)
    build(scl).load(cpu)
    cc = compile_chart(parse_chart(chart, "seq.s7g"))
    install_all(cpu, [GraphFB(cc)])
    prepare_calls(cpu, cc.chart)
    cpu.start()
    cpu.scan()
    assert cpu.mode is CpuMode.RUN and cpu.mem.get("MW12") == 11
