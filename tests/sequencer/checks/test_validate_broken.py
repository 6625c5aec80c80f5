"""Each broken chart in ``broken/`` states its expected diagnostic in its first line
(``// expect: CODE line:col``, and ``(step S2)`` when it names the element it concerns); the
front end must report exactly that code there. A chart
with an S7-SCL source of the same name beside it is checked against that source's blocks
(``s7graph check CHART.s7g --blocks CHART.scl``: E047); a chart without errors also against
a default CPU's memory, as ``s7graph check`` checks it (W140)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.checks.default_cpu import default_cpu_warnings
from s7graph.sequencer.checks.diagnostics import CODES, Diagnostic
from s7graph.sequencer.checks.interfaces import program_blocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from s7graph.sfb import SYSTEM_BLOCKS
from s7graph.steps.scl import compile_scl
from tests.sequencer.helpers import BROKEN

FILES = sorted(BROKEN.glob("*.s7g"))


def diagnostics_of(path: Path) -> list[Diagnostic]:
    scl = path.with_suffix(".scl")
    blocks = None
    if scl.exists():
        program = compile_scl(scl.read_text(encoding="utf-8"), scl.name, blocks=SYSTEM_BLOCKS)
        blocks = program_blocks(program.blocks, program.instances, sources=scl.name)
    try:
        chart = parse_chart(path.read_text(encoding="utf-8"), path.name)
    except ChartSyntaxError as exc:
        return exc.diagnostics
    found = validate(chart, blocks=blocks)
    if not any(d.is_error for d in found):  # as s7graph check adds them (it knows no CPU)
        found += default_cpu_warnings(chart)
    return found


def expectation(path: Path) -> tuple[str, int, int]:
    m = _EXPECT.match(path.read_text(encoding="utf-8"))
    assert m, f"{path.name} lacks its '// expect: CODE line:col' header"
    return m.group(1), int(m.group(2)), int(m.group(3))


_EXPECT = re.compile(r"// expect: (\w+) (\d+):(\d+)(?: \((.+)\))?")
NAMED = [p for p in FILES if (m := _EXPECT.match(p.read_text(encoding="utf-8"))) and m.group(4)]


@pytest.mark.parametrize("path", NAMED, ids=[p.stem for p in NAMED])
def test_a_syntax_error_names_the_step_or_transition_it_lies_in(path: Path) -> None:
    m = _EXPECT.match(path.read_text(encoding="utf-8"))
    assert m is not None
    code, line, col = expectation(path)
    found = {(d.code, d.loc.line, d.loc.col): d.element for d in diagnostics_of(path)}
    assert found[code, line, col] == m.group(4)


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_broken_chart_reports_its_code_at_its_line_and_column(path: Path) -> None:
    code, line, col = expectation(path)
    found = [(d.code, d.loc.line, d.loc.col) for d in diagnostics_of(path)]
    assert (code, line, col) in found, found
    assert all(d.loc.file == path.name for d in diagnostics_of(path))


def test_every_diagnostic_code_has_a_broken_chart() -> None:
    covered = {expectation(p)[0] for p in FILES}
    assert set(CODES) - covered == {"W110"}  # limits: see test_validate.py


def test_broken_chart_code_matches_its_severity() -> None:
    for path in FILES:
        code, line, col = expectation(path)
        d = next(
            d for d in diagnostics_of(path) if (d.code, d.loc.line, d.loc.col) == (code, line, col)
        )
        assert d.severity == ("error" if code.startswith("E") else "warning")
