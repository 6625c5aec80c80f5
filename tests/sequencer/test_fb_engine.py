"""GraphFB in a CPU: OB1 calls, OB100 with INIT_SQ, step events in the ScanRecord, state in
the instance DB (docs/semantics.md, "One FB call", docs/architecture.md, "The core is a
function")."""

from __future__ import annotations

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, StepEvent, install_all
from s7graph.sequencer.state import GraphState
from s7graph.sequencer.text.parse import parse_chart

TEXT = """FUNCTION_BLOCK "Seq" FB 3 DB 4
SEQUENCE 1 "s"
  INITIAL_STEP S1 "a": N Q0.0; END_STEP
  STEP S2 "b": N Q0.1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def make() -> tuple[Cpu, VirtualClock, GraphFB]:
    clock = VirtualClock()
    cpu = Cpu(clock)
    g = GraphFB(compile_chart(parse_chart(TEXT, "seq.s7g")))
    install_all(cpu, [g])
    return cpu, clock, g


def test_ob100_initializes_and_ob1_runs_the_sequencer_with_step_events() -> None:
    cpu, clock, g = make()
    cpu.start("warm")
    assert g.state.active == [0]
    cpu.mem.periph_in[0] = 1
    clock.advance(10)
    rec = cpu.scan()
    assert StepEvent("Seq", 4, 1, "S0", rec.cycle) in rec.events
    assert StepEvent("Seq", 4, 2, "S1", rec.cycle) in rec.events
    assert cpu.mem.get("Q0.1") and g.outputs["S_NO"] == 2


def test_instance_db_snapshot_restores_the_sequencer_exactly() -> None:
    cpu, clock, g = make()
    cpu.start("warm")
    cpu.mem.periph_in[0] = 1
    for _ in range(3):
        clock.advance(10)
        cpu.scan()
    snap = g.idb.snapshot()
    _cpu2, _, g2 = make()
    g2.idb.restore(snap)
    assert isinstance(g2.state, GraphState) and g2.state == g.state


def test_several_graph_fbs_share_one_cpu() -> None:
    clock = VirtualClock()
    cpu = Cpu(clock)
    cc = compile_chart(parse_chart(TEXT, "seq.s7g"))
    a, b = GraphFB(cc, fb_number=1, db_number=1), GraphFB(cc, fb_number=2, db_number=2)
    install_all(cpu, [a, b])
    cpu.start("warm")
    clock.advance(10)
    cpu.scan()
    assert a.state.active == [0] and b.state.active == [0] and a.state is not b.state


def test_a_program_calling_a_pin_outside_the_parameter_set_stops_with_the_set_named() -> None:
    """docs/semantics.md, "FB pins": HALT_SQ is a MAXIMUM pin; a program passing it to a STANDARD FB
    is a programming error naming the parameter set (OB121 absent: STOP, diagnostic entry)."""
    from s7graph.engine.blocks import ob

    graph = GraphFB(compile_chart(parse_chart(TEXT, "seq.s7g")))
    cpu = Cpu(VirtualClock())
    graph.install(cpu)

    @ob(1)
    def main(ctx: object) -> None:
        graph.call(ctx, HALT_SQ=True)

    cpu.load(main)
    cpu.start()
    cpu.scan()
    assert str(cpu.mode) == "STOP"
    messages = [e.message for e in cpu.diagnostics.since(0)]
    assert any("pin HALT_SQ is not in parameter set STANDARD" in m for m in messages), messages
