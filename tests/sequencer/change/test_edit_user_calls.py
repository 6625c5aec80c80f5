"""The editing session checks a chart's calls of the CPU's user blocks against their
interfaces as a chart-only download does (``sequencer.change.edit.diagnostics_of``,
``sequencer.calls.unfit_calls``): a call that does not fit its block is E047 in the
session's diagnostics, the edit made and the chart kept, before any download refuses it. A
call of a block the CPU lacks is left to the swap, as the download leaves it; without the
blocks the calls are not checked."""

from __future__ import annotations

from typing import Any

import pytest

from s7graph import sfb
from s7graph.sequencer.calls import unfit_calls
from s7graph.sequencer.change.base import Edit
from s7graph.sequencer.change.edit import Session, make_edit
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import parse_chart
from s7graph.steps.scl import compile_scl
from tests.sequencer.test_user_fb_members import SCL, chart_text, interfaces

FC5 = """
FUNCTION FC5 : VOID
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT r : INT; END_VAR
  r := a + 1;
END_FUNCTION
"""
UNFIT = {  # S2's call as typed → the E047 the download refuses it with
    "CALL FB 17, DB 12 (start := TRUE, nope := 1)": "FB17 has no parameter nope",
    "CALL FB 17, DB 12 (start := 2.5)": "FB17: start is BOOL, REAL does not fit it",
    "CALL FB 17, DB 12 (start := TRUE, Running := TRUE)": "FB17: Running is an output",
    "CALL FB 17 (start := TRUE)": "FB17 is an FB and needs an instance DB",
    "CALL FC 5, DB 13 (a := 1, r => MW20)": "FC5 is an FC and takes no instance DB",
    "CALL FC 5 (r => MW20)": "FC5: an FC takes every parameter; a missing",
}


def _blocks() -> ProgramBlocks:
    return interfaces(compile_scl(SCL + FC5, "motor.scl", blocks=sfb.SYSTEM_BLOCKS).blocks)


def _calls(session: Session) -> list[str]:
    return [d.message for d in session.diagnostics if d.code == "E047"]


def _call_row(call: str) -> Edit:
    row = {"qualifier": "CALL", "operand": call.removeprefix("CALL ")}
    return make_edit("change_row", {"step": 2, "index": 0, "row": row})


@pytest.mark.parametrize("call", list(UNFIT))
def test_a_call_that_does_not_fit_the_cpus_block_is_e047_in_the_session(call: str) -> None:
    blocks = _blocks()
    session = Session.open(parse_chart(chart_text(), "line.s7g"), None, blocks)
    assert not session.has_errors
    edited = session.apply(_call_row(call))
    assert edited.refusal is None and edited.has_errors  # listed, the chart kept
    (message,) = _calls(edited)
    assert message.startswith(UNFIT[call])
    (found,) = [d for d in edited.diagnostics if d.code == "E047"]
    assert found.element == "step S2 row 1"
    assert [d.message for d in unfit_calls(edited.chart, None, blocks)] == [message]
    assert not edited.undo().has_errors


def test_the_session_lists_every_call_the_download_refuses_and_nothing_else() -> None:
    text = chart_text(call="CALL FB 17, DB 12 (start := 2.5, nope := 1); CALL FB 19, DB 14")
    text = text.replace("N Q0.0;", "CALL FC 5, DB 13 (a := 1, r => MW20);")
    chart = parse_chart(text, "line.s7g")
    blocks = _blocks()
    session = Session.open(chart, None, blocks)
    got = [d for d in session.diagnostics if d.is_error]
    assert got == unfit_calls(chart, None, blocks)  # the download's findings, in order
    assert len(got) == 3 and not any("FB19" in d.message for d in got)  # the swap's to judge


def test_without_the_cpus_blocks_calls_are_unchecked_until_the_session_gets_them() -> None:
    text = chart_text().replace("(start := TRUE)", "(start := TRUE, nope := 1)")
    text = text.replace('"Motor_DB".Running', "I0.1")  # no read needing the blocks
    session = Session.open(parse_chart(text, "line.s7g"))
    assert _calls(session) == [] and not session.has_errors
    given = session.with_blocks(_blocks())
    assert [m[:26] for m in _calls(given)] == ["FB17 has no parameter nope"]
    assert given.has_errors and given.chart is session.chart
    assert _calls(given.with_blocks(None)) == []


def test_against_the_cpus_blocks_the_validator_leaves_the_swaps_judgements_out() -> None:
    """``validate(held=…)``: a call of the CPU's block is judged as ``--blocks`` judges it;
    a block the CPU lacks and an instance DB that is a global DB are the swap's, which
    ``validate(blocks=…)`` (``s7graph check --blocks``) reports."""
    dbs = "DATA_BLOCK DB12\nSTRUCT a : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n"
    program = compile_scl(SCL + FC5 + dbs, "motor.scl", blocks=sfb.SYSTEM_BLOCKS)
    blocks = interfaces(program.blocks)
    call = "CALL FB 17, DB 12 (start := TRUE, nope := 1); CALL FB 19, DB 14"
    chart = parse_chart(chart_text(call=call), "line.s7g")
    checked = [d.message for d in validate(chart, None, blocks=blocks) if d.code == "E047"]
    held = [d.message for d in validate(chart, None, held=blocks) if d.code == "E047"]
    assert [m[:26] for m in held] == ["FB17 has no parameter nope"]
    assert held[0] in checked
    assert any(m.startswith("FB 19 is not in the program's blocks") for m in checked)
    assert any(m.startswith("DB12 is a global DB of the program") for m in checked)


def test_the_editor_checks_a_chart_against_the_cpus_blocks_in_one_pass(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    passes: list[object] = []

    def counted(*args: Any, **kw: Any) -> list[Diagnostic]:
        passes.append(kw.get("held"))
        return validate(*args, **kw)

    monkeypatch.setattr("s7graph.sequencer.change.edit.validate", counted)
    blocks = _blocks()
    session = Session.open(parse_chart(chart_text(), "line.s7g"), None, blocks)
    assert passes == [blocks]
    edited = session.apply(_call_row("CALL FB 17, DB 12 (start := 2.5)"))
    assert passes == [blocks, blocks] and edited.has_errors
