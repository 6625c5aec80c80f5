"""ST bodies a GRAPH row cannot hold run as SCL FCs (docs/import-export.md): the import
makes each one an FC of the chart's SCL source, whose parameters are the chart variables
it reads and writes, and calls it where the body ran — the step's row, or PERMANENT BEFORE
for a transition's result — so the chart compiled with that source runs every body; a body
the SCL compiler refuses stays a PENDING SCL comment, warned at the SCL error."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from s7graph.sequencer.exchange import import_chart, import_file
from s7graph.sequencer.text.format import format_chart, format_row
from s7graph.sequencer.text.model import BlockCall
from s7graph.web.harness.session import ChartSession
from tests.sequencer.exchange.helpers import codes, import_to, scl_session, synthetic


def _watch(session: ChartSession, names: list[str], cycles: int) -> list[tuple[Any, ...]]:
    out = []
    for _ in range(cycles):
        session.scan()
        out.append(tuple(session.get(n) for n in names))
    return out


def test_an_action_body_with_if_else_and_a_for_loop_runs_as_an_scl_fc() -> None:
    """Heat (IF/ELSE, FOR, CODESYS's END_IF without ``;``) is FC 2, called from a row of
    Heating with the variables it reads as inputs and those it writes as outputs; run, it
    writes them every cycle the step is active."""
    result = import_file(synthetic("codesys_scl_bodies.xml"))
    heating = result.chart.all_steps()[1]
    [row] = heating.actions
    assert format_row(row) == (
        "CALL FC 2 (level := level, heater_IN := heater, total_IN := total, i_IN := i, "
        "phase_IN := phase, heater => heater, total => total, i => i, phase => phase);"
    )
    [heat] = [f for f in result.functions if f.item.name == "Heat"]
    assert heat.number == 2 and "FOR i := 1 TO level DO" in heat.source
    assert "END_IF;\ntotal := 0;" in heat.source and "END_FOR;\nphase" in heat.source
    s = scl_session(result)
    s.set("level", 5)
    s.set("start", True)
    seen = _watch(s, ["S2.X", "heater", "total", "i", "phase"], 3)
    assert seen == [
        (True, False, 0, 0, 0),  # T1 switches: Heating is active from the next call on
        (True, True, 15, 6, 1),  # 1 + … + 5, the loop variable past the end as IEC leaves it
        (True, True, 15, 6, 2),
    ]
    s.set("level", 60)
    assert _watch(s, ["heater", "total"], 1) == [(False, 1830)]


def test_a_transition_body_with_case_computes_its_result_and_switches_the_chart() -> None:
    """Ready's CASE is FC 1, called in PERMANENT BEFORE with ``Ready => Ready``: the
    transition reads the value computed in the same call and leaves Heating once phase
    passes 2."""
    result = import_file(synthetic("codesys_scl_bodies.xml"))
    assert result.chart.before == (result.functions[0].call,)
    assert "CALL FC 1 (phase := phase, total := total, Ready => Ready);" in format_chart(
        result.chart
    )
    assert "TRANSITION T2 FROM S2 TO S1 := Ready;" in format_chart(result.chart)
    s = scl_session(result)
    s.set("level", 5)
    s.set("start", True)
    s.scan()
    s.set("start", False)
    seen = _watch(s, ["S1.X", "S2.X", "phase", "Ready"], 5)
    assert seen == [
        (False, True, 1, False),
        (False, True, 2, False),
        (False, True, 3, False),
        (True, False, 4, True),  # phase 3 and total 15 > 10: Ready, T2 switches
        (True, False, 4, True),
    ]


def test_a_body_the_scl_compiler_refuses_stays_pending_warned_at_the_scl_error() -> None:
    """Log calls WriteLog, which no SCL source has: it stays a PENDING SCL comment on its
    step and in ``pending``, warned (I021) at the name the SCL compiler refuses; the bodies
    it accepts are reported too (I033), and nothing else is left out."""
    result = import_file(synthetic("codesys_scl_bodies.xml"))
    assert codes(result.problems) == [("I033", 36), ("I021", 53), ("I033", 63)]
    heat, log, ready = result.problems
    assert (log.loc.line, log.loc.col) == (53, 15)
    assert "action Log: an IF statement" in log.message
    assert "SCL compiler refuses it as an FC (E211: unknown name 'WriteLog')" in log.message
    assert "the body is SCL FC 2" in heat.message and "PERMANENT BEFORE" in ready.message
    assert [(p.kind, p.name, p.step) for p in result.pending] == [("action", "Log", 2)]
    assert result.chart.all_steps()[1].comment.startswith("(* PENDING SCL: action Log")
    assert [f.item.name for f in result.functions] == ["Ready", "Heat"]


def test_a_pou_body_and_a_refused_pou_body() -> None:
    """A POU body beside the SFC is an FC called in PERMANENT BEFORE; one the compiler
    refuses stays in the end comment."""
    text = (
        b"PROGRAM P\nVAR go : BOOL; n : INT; END_VAR\n"
        b"IF go THEN n := n + 1; END_IF;\n"
        b"INITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n"
        b"TRANSITION FROM A TO B := go; END_TRANSITION\n"
        b"TRANSITION FROM B TO A := n > 3; END_TRANSITION\nEND_PROGRAM\n"
    )
    result = import_chart(text, "p.st")
    [call] = result.chart.before
    assert isinstance(call, BlockCall) and (call.kind, call.block) == ("FC", 1)
    assert not result.pending
    refused = import_chart(text.replace(b"n + 1", b"SCALE(n)"), "p.st")
    assert [(d.code, d.loc.line, d.loc.col) for d in refused.problems] == [("I021", 3, 17)]
    assert refused.chart.before == () and refused.blocks_scl == ""
    assert "PENDING SCL: body P" in format_chart(refused.chart)


def test_import_writes_the_scl_source_beside_the_chart(tmp_path: Path) -> None:
    status, chart = import_to(tmp_path, synthetic("codesys_scl_bodies.xml"))
    assert status == 1
    scl = chart.with_suffix(".scl").read_text(encoding="utf-8")
    assert "FUNCTION FC1 : VOID" in scl and "FUNCTION FC2 : VOID" in scl
    assert "CALL FC 2 (" in chart.read_text(encoding="utf-8")
