"""An instance DB's variables read by name in a chart (S7-SCL's structured access to a data
block: ``DB10.Q``, ``"T_S2".Q`` where a symbol of the chart's ``SYMBOLS`` or of the symbol
table names DB 10): in transitions, interlocks, supervisions and on the right of an
assignment; checked against the chart's calls and the block's outputs (E048), never written
(E045); formatted back as written, cross-referenced as a read — by symbol or number, one
operand — exported (a read by number of a DB without a symbol refused by SimaticML, located)."""

from __future__ import annotations

import pytest

from s7graph import sfb
from s7graph.engine import Cpu, CpuMode, VirtualClock
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer import calls as runtime_calls
from s7graph.sequencer.calls import prepare_calls
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.exchange import export_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.call_sites import call_sites
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


def test_simaticml_export_refuses_a_read_by_number_of_a_db_no_symbol_names() -> None:
    """TIA names a DB; the exports themselves: tests/sequencer/exchange/test_db_reads.py."""
    why = r"m\.s7g:12:34: DB10\.Q: TIA reads a DB's variables by the DB's name, and DB 10 has none"
    with pytest.raises(ValueError, match=why):
        export_chart(parse_chart(chart_text(), "m.s7g"), "simaticml")


def with_db_symbol(text: str, declaration: str = '"T_S2" : DB 10 : SFB4;') -> str:
    """``text`` with the chart's own ``SYMBOLS`` section holding ``declaration``."""
    return text.replace("VAR elapsed", f"SYMBOLS {declaration} END_SYMBOLS\nVAR elapsed", 1)


def test_a_db_symbol_of_the_charts_own_symbols_reads_the_same_variable() -> None:
    text = with_db_symbol(chart_text('"T_S2".Q', interlock='INTERLOCK := NOT "t_s2".Q;'))
    cpu, clock, g = run(text)
    scan_until(cpu, clock, 1900)
    assert g.state.active == [1]
    scan_until(cpu, clock, 300)
    assert g.state.active == [2]


def test_the_charts_db_symbol_comes_before_the_symbol_tables() -> None:
    table = SymbolTable()
    table.add("T_S2", "DB 11")
    assert errors(with_db_symbol(chart_text('"T_S2".Q')), table) == []


@pytest.mark.parametrize(
    ("declaration", "condition", "code", "why"),
    [
        ('"T_S2" : DB10 : SFB4;', '"T_S2"', "E040", '"T_S2" is DB 10, not an operand'),
        ('"Start" : I0.0 : BOOL;', '"Start".Q', "E048", '"Start" is the operand I0.0, not a DB'),
        ('"T_S2" : DB0 : SFB4;', "DB10.Q", "E041", "DB 0: a block number is 1 to 65535"),
    ],
)
def test_a_charts_symbol_in_the_wrong_place_is_an_error_naming_it(
    declaration: str, condition: str, code: str, why: str
) -> None:
    (found,) = errors(with_db_symbol(chart_text(condition), declaration))
    assert found[0] == code and why in found[3]


def test_the_formatter_writes_a_db_symbol_back() -> None:
    chart = parse_chart(with_db_symbol(chart_text('"T_S2".Q'), '"T_S2":DB 10:SFB4;'), "m.s7g")
    formatted = format_chart(chart)
    assert '"T_S2" : DB10 : SFB4;' in formatted
    assert unlocated(parse_chart(formatted, "m.s7g")) == unlocated(chart)


def test_cross_references_list_a_variable_by_its_db_symbol_and_number_as_one_operand() -> None:
    table = SymbolTable()
    table.add("T_S2", "DB 10")
    text = chart_text(
        '"t_s2".q', interlock="INTERLOCK := NOT DB10.Q;", rows="N elapsed := DB10.ET;"
    )
    refs = cross_references(parse_chart(text, "m.s7g"), table)
    uses = refs.operands()
    shown = '"T_S2".Q (DB10.Q)'
    assert [(u.element, u.access) for u in uses[shown]] == [
        ('S2 "b" interlock', "read"),
        ("T2", "read"),
    ]
    assert '"T_S2".ET (DB10.ET)' in uses and "DB10.Q" not in uses
    assert [u.element for u in refs.of("DB10.q")] == ['S2 "b" interlock', "T2"]


def test_a_db_symbol_of_the_chart_read_by_name_is_used() -> None:
    text = with_db_symbol(chart_text("DB10.Q"))
    refs = cross_references(parse_chart(text, "m.s7g"))
    assert refs.unused == () and '"T_S2".Q (DB10.Q)' in refs.operands()


def test_the_text_and_the_runtime_walk_a_charts_calls_the_one_way() -> None:
    permanent = 'PERMANENT AFTER CALL "TON", DB 11 (IN := S2.X, PT := T#1S); END_PERMANENT\n'
    text = chart_text("DB11.Q AND DB10.Q").replace("SEQUENCE 1", permanent + "SEQUENCE 1", 1)
    chart = parse_chart(text, "m.s7g")
    assert errors(text) == []  # DB 11 is named by a permanent instruction's call
    sites = [(s.call.instance, s.element) for s in call_sites(chart)]
    assert sites == [(10, "step S2 row 1"), (11, "permanent after")]
    assert runtime_calls.call_sites is call_sites  # prepare_calls walks them so
