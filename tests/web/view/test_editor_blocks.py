"""The editor checks a chart against the S7-SCL blocks the CPU runs (``web.view.editor_cpu.
cpu_blocks``): their sources come with the running chart's source (``ChartSource.blocks``)
and are compiled in the view with the CPU's symbol table and the chart's SYMBOLS, so a
read of an FB's variable by name shows no E048 where a download takes it, and E048 naming
the variable where the FB lacks it — in the diagnostics the page lists by line and column.
Sources too large to come with the chart, or that do not compile, give no interfaces and a
note saying so. A call of those blocks that does not fit them is E047 at its line and
column, the very lines a download's compile refuses it with (``web.bus.compile_jobs``)."""

from __future__ import annotations

from s7graph.sequencer.change.edit import Session
from s7graph.sequencer.change.typed import parse_source
from s7graph.sequencer.checks.diagnostics import format_diagnostic
from s7graph.sequencer.text.format import format_chart
from s7graph.web.bus import compile_jobs
from s7graph.web.bus.protocol import ChartSource
from s7graph.web.view.editor import _located
from s7graph.web.view.editor_cpu import cpu_blocks
from tests.sequencer.change.test_edit_user_calls import FC5
from tests.sequencer.test_user_fb_members import SCL, chart_text


def _source(text: str, **blocks: str) -> ChartSource:
    files = {f"{name}.scl": t for name, t in blocks.items()}
    return ChartSource(fb="Line", file="line.s7g", text=text, blocks=files)


def test_the_editor_reads_an_fbs_variable_in_the_blocks_the_cpu_runs() -> None:
    text = chart_text('"Motor_DB".Running AND DB12.calls > 2')
    chart = parse_source(text, "line.s7g")
    blocks, note = cpu_blocks(_source(text, motor=SCL), chart)
    assert note == "" and blocks is not None and blocks.sources == "motor.scl"
    session = Session.open(chart, None, blocks)
    assert not session.has_errors
    assert [d.code for d in _located(chart, None, blocks).diagnostics if d.is_error] == []
    assert [d.code for d in _located(chart, None).diagnostics if d.is_error] == ["E048"] * 2


def test_a_variable_the_cpus_fb_lacks_is_e048_at_its_line_and_column() -> None:
    text = chart_text("DB12.Nope")
    chart = parse_source(text, "line.s7g")
    blocks, _ = cpu_blocks(_source(text, motor=SCL), chart)
    (found,) = [d for d in _located(chart, None, blocks).diagnostics if d.is_error]
    shown = format_chart(chart).splitlines()  # as the source view writes it
    line = next(n for n, x in enumerate(shown, 1) if "DB12.Nope" in x)
    assert (found.code, found.loc.line) == ("E048", line)
    assert shown[line - 1][found.loc.col - 1 :].startswith("DB12.Nope")
    assert "Nope is not a variable of FB17" in found.message


def test_without_the_cpus_sources_the_editor_has_no_interfaces_and_says_why() -> None:
    text = chart_text()
    chart = parse_source(text, "line.s7g")
    assert cpu_blocks(_source(text), chart) == (None, "")
    left = ChartSource(fb="Line", text=text, left_out=["motor.scl"])
    blocks, note = cpu_blocks(left, chart)
    assert blocks is None and "motor.scl are too large to come with its chart" in note
    blocks, note = cpu_blocks(_source(text, motor=SCL.replace("END_VAR", "END_VR", 1)), chart)
    assert blocks is None and note.startswith("the CPU's S7-SCL sources do not compile here: ")


def test_a_call_that_does_not_fit_the_cpus_blocks_is_e047_as_the_download_refuses_it() -> None:
    running = chart_text()
    text = running.replace("(start := TRUE)", "(start := 2.5, nope := 1)")
    text = text.replace("N Q0.0;", "CALL FC 5, DB 13 (a := 1, r => MW20); CALL FB 19, DB 14;")
    chart = parse_source(text, "line.s7g")
    blocks, _ = cpu_blocks(_source(running, motor=SCL, fc=FC5), chart)
    assert blocks is not None
    found = [d for d in _located(chart, None, blocks).diagnostics if d.is_error]
    assert [(d.code, d.message[:26]) for d in found] == [
        ("E047", "FB17 has no parameter nope"),
        ("E047", "FB17: start is BOOL, REAL "),
        ("E047", "FC5 is an FC and takes no "),
    ]  # FB19, which the CPU lacks, is the swap's to judge
    shown = format_chart(chart).splitlines()  # as the source view writes it
    assert shown[found[1].loc.line - 1][found[1].loc.col - 1 :].startswith("2.5")
    assert Session.open(chart, None, blocks).has_errors  # the page's Download refuses
    request = {"op": "preview", "text": format_chart(chart), "file": "line.s7g"}
    answer, _ = compile_jobs.answer({**request, "interfaces": blocks, "running": running})
    assert answer["lines"] == [format_diagnostic(d) for d in found]
