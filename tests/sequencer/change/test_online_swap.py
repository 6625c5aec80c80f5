"""An online change swaps everything the running GraphFB derives from its chart at once:
after a download the step events, the FB's interface, the display and the fast path are
those of the new chart, whatever it adds, removes or renumbers (``sequencer.fb.LoadedChart``,
``sequencer.change.online.swap``)."""

from __future__ import annotations

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.modes import CpuMode
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.online import SwapRefused, swap
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from tests.paths import ROOT

CHAIN = """FUNCTION_BLOCK "Seq" FB 1 DB 1
SEQUENCE 1 "A"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S6 "Six":
    N Q0.6;
  END_STEP
  STEP S7 "Seven":
    N Q0.7;
  END_STEP
  TRANSITION T1 FROM S1 TO S6 := I0.0;
  TRANSITION T2 FROM S6 TO S7 := I0.0;
  TRANSITION T3 FROM S7 TO S1 := I0.0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""

# S8 inserted between S6 and S7, as the editor's "insert step" does
WITH_S8 = (
    CHAIN.replace(
        '  STEP S7 "Seven":', '  STEP S8 "Eight":\n    N Q1.0;\n  END_STEP\n  STEP S7 "Seven":'
    )
    .replace("FROM S6 TO S7", "FROM S6 TO S8")
    .replace("  TRANSITION T3", "  TRANSITION T4 FROM S8 TO S7 := I0.0;\n  TRANSITION T3")
)


def _cc(text: str, symbols: SymbolTable | None = None) -> CompiledChart:
    return compile_chart(parse_chart(text, "chart.s7g"), symbols)


def _running(text: str, symbols: SymbolTable | None = None) -> tuple[Cpu, VirtualClock, GraphFB]:
    clock = VirtualClock()
    cpu = Cpu(clock)
    cpu.mem.symbols = symbols
    g = GraphFB(_cc(text, symbols))
    install_all(cpu, [g])
    cpu.start("warm")
    return cpu, clock, g


def _steps_of(cpu: Cpu, clock: VirtualClock, scans: int) -> list[str]:
    out: list[str] = []
    for _ in range(scans):
        clock.advance(10)
        record = cpu.scan()
        assert cpu.mode is CpuMode.RUN, cpu.diagnostics
        out += [f"S{e.step} {e.event}" for e in record.events]
    return out


def test_a_step_inserted_by_a_download_is_named_in_the_events_and_left_without_a_stop() -> None:
    cpu, clock, g = _running(CHAIN)
    cpu.mem.periph_in[0] = 1
    assert _steps_of(cpu, clock, 1) == ["S1 S0", "S6 S1"]
    swap(g, _cc(WITH_S8), cpu)
    events = _steps_of(cpu, clock, 4)
    assert events == [
        "S6 S0",
        "S8 S1",
        "S8 S0",
        "S7 S1",
        "S7 S0",
        "S1 S1",
        "S1 S0",
        "S6 S1",
    ]
    assert cpu.mode is CpuMode.RUN


def test_after_a_download_nothing_the_fb_derived_from_the_old_chart_is_left() -> None:
    cpu, clock, g = _running(CHAIN)
    _steps_of(cpu, clock, 2)
    old = g.loaded
    new = _cc(WITH_S8.replace('"Seq" FB 1 DB 1', '"Seq" FB 1 DB 1\n  PARAMETERS := MAXIMUM;'))
    swap(g, new, cpu)
    loaded = g.loaded
    assert loaded is not old and g.cc is new
    assert loaded.step_numbers == new.step_numbers and loaded.name == new.name
    assert g.fb is loaded.fb and cpu.blocks.get(g.fb.label) is loaded.fb
    pins = {v.name for v in g.fb.interface}
    assert {"S_SEL", "S_ON", "ERR_FLT", "S_NO"} <= pins  # the new parameter set
    _steps_of(cpu, clock, 2)
    assert g.loaded.runtime is not None and g.loaded.runtime.cc is new  # cycle, display, fast path


def test_a_twenty_step_chain_of_true_transitions_downloaded_into_the_drill_keeps_running() -> None:
    drill = (ROOT / "examples/drill/drill.s7g").read_text(encoding="utf-8")
    table = SymbolTable.from_text((ROOT / "examples/drill/symbols.txt").read_text(encoding="utf-8"))
    cpu, clock, g = _running(drill, table)
    _steps_of(cpu, clock, 3)
    steps = "".join(
        f"  {'INITIAL_STEP' if k == 1 else 'STEP'} S{k}:\n    N Q4.{k % 8};\n  END_STEP\n"
        for k in range(1, 21)
    )
    moves = "".join(
        f"  TRANSITION T{k} FROM S{k} TO S{k % 20 + 1} := TRUE;\n" for k in range(1, 21)
    )
    chain = (
        'FUNCTION_BLOCK "Seq_drill" FB 1 DB 1\nSEQUENCE 1 "Chain"\n'
        f"{steps}{moves}END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    swap(g, _cc(chain), cpu, removed="keep")
    events = _steps_of(cpu, clock, 40)
    entered = [int(e.split()[0][1:]) for e in events if e.endswith("S1")]
    assert entered[:20] == [*range(2, 21), 1]  # every step in turn, one a call


def test_an_active_step_a_download_removes_leaves_no_n_output_on() -> None:
    """docs/online-change.md: a removed active step gets its final scan at the swap, as if
    it were left: its N operand goes back to 0 (kept or initialized alike)."""
    for removed in ("keep", "init"):
        cpu, clock, g = _running(CHAIN)
        cpu.mem.periph_in[0] = 1
        assert _steps_of(cpu, clock, 1) == ["S1 S0", "S6 S1"]
        cpu.mem.periph_in[0] = 0
        _steps_of(cpu, clock, 1)
        assert cpu.mem.periph_out[0] == 0x40  # Q0.6 of the active S6
        without = (
            CHAIN.replace('  STEP S6 "Six":\n    N Q0.6;\n  END_STEP\n', "")
            .replace("FROM S1 TO S6", "FROM S1 TO S7")
            .replace("  TRANSITION T2 FROM S6 TO S7 := I0.0;\n", "")
        )
        swap(g, _cc(without), cpu, removed=removed)
        clock.advance(10)
        cpu.scan()
        assert cpu.mem.periph_out[0] & 0x40 == 0, removed


def test_a_download_reaching_beyond_the_cpus_memory_is_refused_and_the_cpu_runs_on() -> None:
    """A chart with ``N Q9999.7`` (or a DB the CPU lacks) passes ``check``, which knows no
    CPU; downloaded, it would stop the CPU when the FB first runs it. The swap refuses it
    naming the operand, and the old chart goes on."""
    for operand, why in (
        ("Q9999.7", "Q9999.7 is outside the Q area (128 bytes)"),
        ("DB99.DBX0.0", "DB99 does not exist"),
    ):
        cpu, clock, g = _running(CHAIN)
        old = g.cc
        with pytest.raises(SwapRefused) as refused:
            swap(g, _cc(CHAIN.replace("N Q0.7;", f"N {operand};")), cpu)
        assert str(refused.value) == f"{why}: reached, the new chart would stop the CPU"
        assert g.cc is old
        cpu.mem.periph_in[0] = 1
        assert _steps_of(cpu, clock, 3) == ["S1 S0", "S6 S1", "S6 S0", "S7 S1", "S7 S0", "S1 S1"]
