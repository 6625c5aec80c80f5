"""The editing session checks a chart's reads of a user FB's variables by name
(``"Motor_DB".Running``) against the interfaces of the CPU's blocks, as a download's compile
does (``sequencer.change.edit.Session``, ``blocks``): a variable the FB has is no error, one
it lacks is E048 naming it; without the blocks E048 says they are needed."""

from __future__ import annotations

from s7graph.sequencer.change.edit import Session, make_edit
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.test_user_fb_members import chart_text, interfaces, scl_program


def _errors(session: Session) -> list[tuple[str, str]]:
    return [(d.code, d.message) for d in session.diagnostics if d.is_error]


def test_a_session_with_the_cpus_blocks_reads_an_fbs_variable_and_refuses_one_it_lacks() -> None:
    blocks = interfaces(scl_program().blocks)
    session = Session.open(parse_chart(chart_text(), "line.s7g"), None, blocks)
    assert _errors(session) == [] and not session.has_errors
    edit = make_edit("set_condition", {"transition": 2, "condition": "DB12.calls > 2"})
    assert _errors(session.apply(edit)) == []
    edit = make_edit("set_condition", {"transition": 2, "condition": "DB12.Nope"})
    edited = session.apply(edit)
    assert edited.refusal is None and edited.has_errors  # listed, the chart kept
    ((code, message),) = _errors(edited)
    assert code == "E048" and "Nope is not a variable of FB17" in message
    assert _errors(edited.undo()) == []


def test_without_the_blocks_the_read_is_e048_until_the_session_gets_them() -> None:
    session = Session.open(parse_chart(chart_text(), "line.s7g"))
    ((code, message),) = _errors(session)
    assert code == "E048" and "only with the program's blocks" in message
    given = session.with_blocks(interfaces(scl_program().blocks))
    assert _errors(given) == [] and given.chart is session.chart
    assert _errors(given.with_blocks(None)) == _errors(session)
