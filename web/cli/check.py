"""``s7graph check CHART.s7g [--symbols FILE] [--blocks BLOCKS.scl …]``: print a chart's
diagnostics (docs/chart-format.md).

One diagnostic a line on stdout (``file:line:col: error[E010]: message (element)``), then a
summary line. Exit status: 0 clean, 1 warnings only, 2 errors (syntax errors included). An
unreadable chart or symbol file is one line on stderr and exit 2. ``--blocks``: the S7-SCL
sources whose blocks the chart's calls are checked against (E047,
``sequencer.checks.user_calls``); their own diagnostics come first and count. An operand
beyond the memory of a default CPU warns (W140, ``sequencer.checks.default_cpu``): the check
knows no CPU.
"""

from __future__ import annotations

import contextlib
import copy
import sys
from collections.abc import Sequence
from pathlib import Path

from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.default_cpu import default_cpu_warnings
from s7graph.sequencer.checks.diagnostics import (
    Diagnostic,
    format_diagnostic,
    sort_key,
    warning,
)
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import ChartSyntaxError, chart_text, parse_chart
from s7graph.web.bus.protocol import ChartLayout, layout_problem
from s7graph.web.harness.scl import ChartBlocks, SclLoadError
from s7graph.web.harness.session import add_chart_symbols


def check_command(chart: Path, symbols: Path | None = None, blocks: Sequence[Path] = ()) -> int:
    """Parse and validate ``chart``; print diagnostics and a summary; return the exit code.
    ``blocks``: S7-SCL sources whose FBs, FCs and DBs the chart's calls are checked against
    (E047); their own diagnostics come first and count."""
    try:
        data = chart.read_bytes()
    except OSError as exc:
        print(f"s7graph: error: cannot read {chart}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    table: SymbolTable | None = None
    if symbols is not None:
        try:
            table = SymbolTable.from_file(symbols)
        except OSError as exc:
            print(
                f"s7graph: error: cannot read symbols {symbols}: {exc.strerror or exc}",
                file=sys.stderr,
            )
            return 2
        except S7Error as exc:
            print(f"s7graph: error: cannot read symbols {symbols}: {exc}", file=sys.stderr)
            return 2
    parsed: Chart | ChartSyntaxError
    try:
        parsed = parse_chart(chart_text(data, str(chart)), str(chart))
    except ChartSyntaxError as exc:
        parsed = exc
    program, lines = _program(blocks, _sources_table(table, parsed))
    if program is None and lines is None:
        return 2
    diags = _diagnostics(parsed, table, program)
    scl_errors = 0
    for line, is_error in lines or []:
        print(line)
        scl_errors += is_error
    for d in diags:
        print(format_diagnostic(d))
    errors = sum(d.severity == "error" for d in diags) + scl_errors
    warnings = len(diags) + len(lines or []) - errors
    print(f"{chart}: {_plural(errors, 'error')}, {_plural(warnings, 'warning')}")
    return 2 if errors else 1 if warnings else 0


def _diagnostics(
    parsed: Chart | ChartSyntaxError, table: SymbolTable | None, program: ProgramBlocks | None
) -> list[Diagnostic]:
    """The chart's diagnostics: its syntax errors, else its validation's, with the default
    CPU's warnings and the view's when it has no error."""
    if isinstance(parsed, ChartSyntaxError):
        return parsed.diagnostics
    try:
        diags = validate(parsed, table, blocks=program)
        if not any(d.severity == "error" for d in diags):
            diags = sorted([*diags, *default_cpu_warnings(parsed, table)], key=sort_key)
            diags += view_diagnostics(parsed)
    except ChartSyntaxError as exc:
        return exc.diagnostics
    return diags


def _sources_table(table: SymbolTable | None, chart: Chart | ChartSyntaxError) -> SymbolTable:
    """The table the ``--blocks`` sources are compiled with: ``table`` with the chart's
    ``SYMBOLS`` in, as ``sim``, ``run`` and ``export`` compile them (a copy: the chart is
    validated against ``table`` as given; a symbol that does not fit is the chart's own
    diagnostic)."""
    out = copy.deepcopy(table) if table is not None else SymbolTable()
    if isinstance(chart, Chart):
        with contextlib.suppress(S7Error):
            add_chart_symbols(chart, out)
    return out


def _program(
    blocks: Sequence[Path], table: SymbolTable | None
) -> tuple[ProgramBlocks | None, list[tuple[str, bool]] | None]:
    """The interfaces of the ``blocks`` sources (None without any) and their diagnostic
    lines (is each an error); (None, None) after one line on stderr when a source cannot
    be read."""
    if not blocks:
        return None, []
    compiled = ChartBlocks(blocks)  # as sim, run and export compile them
    try:
        program = compiled(table)
    except SclLoadError as exc:
        return None, [(line, ": warning[" not in line) for line in exc.lines]
    except S7Error as exc:
        print(f"s7graph: error: {exc}", file=sys.stderr)
        return None, None
    return program, [(line, False) for line in compiled.warnings]


def view_diagnostics(chart: Chart) -> list[Diagnostic]:
    """W110 when the browser view cannot show ``chart`` (its layout breaks a limit of the
    bus protocol: too many steps, an FB name the bus cannot carry, …)."""
    problem = layout_problem(ChartLayout.from_chart(chart))
    if problem is None:
        return []
    return [
        warning("W110", f"the browser view (--web) cannot show this chart: {problem}", chart.loc)
    ]


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"
