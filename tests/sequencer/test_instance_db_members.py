"""An instance DB's variables read by name in a chart (S7-SCL's structured access to a data
block: ``DB10.Q``, ``"T_S2".Q`` where the symbol names DB 10): in transitions, interlocks,
supervisions and on the right of an assignment; checked against the chart's calls and the
block's outputs (E048), never written (E045); formatted back as written, cross-referenced
as a read, refused by the exporters with a located message."""

from __future__ import annotations

import pytest

from s7graph import sfb
from s7graph.engine import Cpu, CpuMode, VirtualClock
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.calls import prepare_calls
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.exchange import export_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import unlocated
from s7graph.sequencer.xref import cross_references


def chart_text(condition: str = "DB10.Q", rows: str = "", interlock: str = "") -> str:
    return f"""FUNCTION_BLOCK "Members" FB 1 DB 1
VAR elapsed : TIME; END_VAR
SEQUENCE 1 "A"
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b":
    {interlock}
    CALL "TON", DB 10 (IN := S2.X, PT := T#2S);
    {rows}
  END_STEP
  STEP S3 "c": N Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := {condition};
  TRANSITION T3 FROM S3 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def run(text: str, symbols: SymbolTable | None = None) -> tuple[Cpu, VirtualClock, GraphFB]:
    clock = VirtualClock()
    cpu = Cpu(clock)
    sfb.install(cpu)
    g = GraphFB(compile_chart(parse_chart(text, "m.s7g"), symbols))
    install_all(cpu, [g])
    assert prepare_calls(cpu, g.cc.chart).created == [10]
    cpu.start("warm")
    cpu.mem.periph_in[0] = 1
    return cpu, clock, g


def scan_until(cpu: Cpu, clock: VirtualClock, ms: int) -> None:
    for _ in range(ms // 100):
        cpu.scan()
        clock.advance(100)


def errors(text: str, symbols: SymbolTable | None = None) -> list[tuple[str, int, int, str]]:
    found = validate(parse_chart(text, "m.s7g"), symbols)
    return [(d.code, d.loc.line, d.loc.col, d.message) for d in found if d.is_error]


def test_a_transition_reads_the_ton_q_by_db_number_and_switches_after_2_s() -> None:
    cpu, clock, g = run(chart_text("DB10.Q"))
    scan_until(cpu, clock, 1900)
    assert g.state.active == [1]
    scan_until(cpu, clock, 300)
    assert g.state.active == [2] and cpu.mode is CpuMode.RUN
    assert cpu.mem.get("Q0.0") is True


def test_an_assignment_reads_the_elapsed_time_into_a_variable() -> None:
    cpu, clock, g = run(chart_text("DB10.ET >= T#1S", rows="N elapsed := DB10.ET;"))
    scan_until(cpu, clock, 800)
    assert g.state.active == [1] and 500 <= g.state.vars["elapsed"] <= 800
    scan_until(cpu, clock, 400)
    assert g.state.active == [2]


def test_a_db_symbol_of_the_symbol_table_reads_the_same_variable() -> None:
    table = SymbolTable()
    table.add("T_S2", "DB 10")
    text = chart_text('"T_S2".Q', interlock='INTERLOCK := NOT "T_S2".Q;')
    cpu, clock, g = run(text, table)
    scan_until(cpu, clock, 2200)
    assert g.state.active == [2]


@pytest.mark.parametrize(
    ("condition", "why"),
    [
        ("DB11.Q", "DB11 is not an instance DB of this chart's calls"),
        ("DB10.IN", "IN is an input of SFB4 TON"),
        ("DB10.NOPE", "NOPE is not a variable of SFB4 TON (its outputs: Q, ET)"),
        ('"T_S2".Q', 'no DB symbol "T_S2"'),
    ],
)
def test_a_variable_the_chart_cannot_read_is_e048_at_its_place(condition: str, why: str) -> None:
    (found,) = errors(chart_text(condition))
    assert found[:3] == ("E048", 12, 34) and why in found[3]


def test_a_symbol_naming_an_operand_is_no_db() -> None:
    table = SymbolTable()
    table.add("Start", "I0.0", "BOOL")
    (found,) = errors(chart_text('"Start".Q'), table)
    assert found[0] == "E048" and "not a DB" in found[3]


@pytest.mark.parametrize("row", ["S DB10.Q;", "N elapsed := DB10.ET; N DB10.ET := T#1S;"])
def test_the_chart_cannot_write_an_instance_db_variable(row: str) -> None:
    (found,) = errors(chart_text(rows=row))
    assert found[0] == "E045" and "the chart only reads it" in found[3]


def test_an_absolute_address_into_the_instance_db_stays_e041() -> None:
    assert [e[0] for e in errors(chart_text("DB10.DBX6.0"))] == ["E041"]


def test_the_formatter_writes_the_access_back_as_written() -> None:
    text = chart_text('DB 10 . Q AND "T_S2".ET > T#1S', rows="N elapsed := DB10.ET;")
    chart = parse_chart(text, "m.s7g")
    formatted = format_chart(chart)
    assert 'DB10.Q AND "T_S2".ET > T#1S' in formatted and "elapsed := DB10.ET" in formatted
    assert unlocated(parse_chart(formatted, "m.s7g")) == unlocated(chart)


def test_cross_references_list_the_access_as_a_read() -> None:
    refs = cross_references(parse_chart(chart_text(rows="N elapsed := DB10.ET;"), "m.s7g"))
    uses = refs.operands()
    assert [(u.element, u.access) for u in uses["DB10.Q"]] == [("T2", "read")]
    assert [u.access for u in uses["DB10.ET"]] == ["read"]


@pytest.mark.parametrize("to", ["plcopen", "simaticml"])
def test_the_exporters_refuse_the_access_with_its_place(to: str) -> None:
    with pytest.raises(ValueError, match=r"m\.s7g:12:34: DB10\.Q: a \w+ export cannot hold"):
        export_chart(parse_chart(chart_text(), "m.s7g"), to)
